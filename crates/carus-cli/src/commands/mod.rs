//! One module per subcommand; each owns its clap arguments and its `run`.

mod batch;
pub mod bench;
pub mod detect;
pub mod measure;
pub mod mesh;
pub mod render;
pub mod run;
pub mod sanity;
pub mod scenarios;
mod settings;
pub mod solve;
pub mod sweep;
pub mod validate;
pub mod view;

/// How a command that ran to completion ended.
#[derive(Debug)]
pub enum Status {
    /// Everything asked for was done (and every check passed).
    Success,
    /// The command ran, but a check it reports failed (exit status 1).
    Failed,
}

/// A flag's value the command cannot take, found after clap parsed it:
/// exit status 2, as clap's own refusals (CONVENTIONS.md: 2 on bad
/// arguments).
#[derive(Debug)]
pub struct BadArgument(pub String);

impl std::fmt::Display for BadArgument {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadArgument {}

/// Returns early with a [`BadArgument`] made as `format!` makes text.
#[macro_export]
macro_rules! bad_argument {
    ($($text:tt)*) => {
        return Err($crate::commands::BadArgument(format!($($text)*)).into())
    };
}

/// Whether a long command shows its progress on standard error: not with
/// `--quiet`, nor when standard error is not a terminal (a log file or a
/// pipe), as CONVENTIONS.md asks.
pub fn shows_progress(quiet: bool) -> bool {
    use std::io::IsTerminal;
    !quiet && std::io::stderr().is_terminal()
}

/// The progress bar of long commands: permille done, elapsed, time left.
pub fn progress_bar() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}, about {eta} left")
            .expect("valid template"),
    );
    bar
}

/// A stop flag that Ctrl-C (or SIGTERM or SIGHUP: a `kill`, a batch
/// scheduler's time limit, a closed terminal) sets: a labour run polls it
/// and stops cleanly with everything so far written; a second one (more
/// than 0.1 s later: one sent to the process and its group arrives twice)
/// quits at once (exit status 130). One handler per process, so the flag is shared and
/// cleared for each command that asks for it.
pub fn ctrl_c_flag() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, OnceLock};
    static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    let flag = FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        let seen = flag.clone();
        // `timeout` and job schedulers signal the process and then its
        // group, so one stop can arrive twice within microseconds: a second
        // signal counts only after this long.
        const SAME_SIGNAL: std::time::Duration = std::time::Duration::from_millis(100);
        let mut first = std::time::Instant::now();
        // Without a handler (it failed to install) Ctrl-C keeps its default: quit.
        let _ = ctrlc::set_handler(move || {
            if !seen.swap(true, Ordering::Relaxed) {
                first = std::time::Instant::now();
            } else if first.elapsed() > SAME_SIGNAL {
                std::process::exit(130);
            }
        });
        flag
    });
    flag.store(false, Ordering::Relaxed);
    flag.clone()
}

/// The threads of a command that runs `runs` labours at once: `jobs` of
/// them, by default one per core, never more than the runs or the cores,
/// whichever is more; also says how many.
pub fn labour_pool(jobs: Option<usize>, runs: usize) -> anyhow::Result<(rayon::ThreadPool, usize)> {
    if jobs == Some(0) {
        crate::bad_argument!("--jobs must be at least 1");
    }
    // The runs' own parallel passes share the pool, so it keeps a thread
    // per core however few the runs; past that, a thread per run is all
    // that can work (a --jobs of 100000 spent its time starting threads).
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = jobs.unwrap_or(cores).min(runs.max(cores));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start {jobs} threads for the runs: {e}"))?;
    Ok((pool, jobs))
}

/// Makes the folder `dir` (and those above it) for a command's output,
/// given with `flag`; a file in its place is named, with the fix.
pub fn create_out_folder(dir: &std::path::Path, flag: &str) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!("{} is a file, not a folder; choose another {flag}", dir.display());
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("cannot create the folder {}: {e}; {}", dir.display(), io_fix(&e, flag)))
}

/// What to do when the system refuses to make or write what `flag` named,
/// by its reason: the OS's words alone ("No such file or directory" for a
/// folder under /proc) do not say.
pub fn io_fix(error: &std::io::Error, flag: &str) -> String {
    use std::io::ErrorKind;
    match error.kind() {
        ErrorKind::NotFound => format!(
            "nothing can be made there (a system folder such as /proc, or a path through a folder or \
             drive that is not there and cannot be made); choose another {flag}, in a folder you can write"
        ),
        ErrorKind::PermissionDenied => {
            format!("you may not write there; choose another {flag}, in a folder you can write, or change its permissions")
        }
        ErrorKind::ReadOnlyFilesystem => format!("that disk is read-only; choose another {flag} on a writable disk"),
        ErrorKind::StorageFull | ErrorKind::QuotaExceeded => format!("free some space, or choose another {flag} on another disk"),
        ErrorKind::IsADirectory => format!("a folder has that name; give {flag} a file's name (in that folder, say)"),
        ErrorKind::NotADirectory => format!("a file stands where a folder above it should be; choose another {flag}"),
        _ => format!("choose another {flag}, in a folder you can write"),
    }
}

/// Refuses a folder given for the picture `flag` names, before anything is
/// drawn (writing would fail with the OS's bare "Is a directory").
pub fn check_picture_path(path: &std::path::Path, flag: &str) -> anyhow::Result<()> {
    if path.is_dir() {
        crate::bad_argument!(
            "{flag} {0} is a folder; give the picture's file name, e.g. {flag} {1}",
            path.display(),
            path.join("picture.png").display()
        );
    }
    Ok(())
}

/// Writes a picture as a PNG whole, or leaves none (a full disk would
/// leave an empty or cut file that reads as a damaged picture); an earlier
/// file that cannot be opened is left as it was. `flag` named the path.
pub fn save_picture(picture: &carus_render::Image, path: &std::path::Path, flag: &str) -> anyhow::Result<()> {
    carus_io::output::write_whole(path, &picture.encode_png()?)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}; {}", path.display(), io_fix(&e, flag)))
}

/// The largest test cube `carus validate cube` and `carus bench tled`
/// build: 20 million elements (an H8 cube of 271 per edge, a T4 one of
/// 149), several GB of model and state; beyond it the allocation itself
/// would abort the program.
const MOST_CUBE_ELEMENTS: usize = 20_000_000;

/// Whether `dir` is a run's folder: its scenario with its record or a
/// checkpoint.
pub fn holds_run(dir: &std::path::Path) -> bool {
    use carus_labour::output::{CHECKPOINT_FILE, RUN_FILE, SCENARIO_FILE};
    dir.join(SCENARIO_FILE).is_file() && [RUN_FILE, CHECKPOINT_FILE].iter().any(|f| dir.join(f).is_file())
}

/// Whether `dir` is a folder of runs: a sweep's or sanity's, whose tables
/// were written from the runs in it.
pub fn holds_batch(dir: &std::path::Path) -> bool {
    [sweep::PLAN_FILE, sanity::PLAN_FILE].iter().any(|plan| dir.join(plan).is_file())
}

/// What a folder that carus wrote is, said when a command is given the
/// wrong kind: the commands that take it. None for a folder of no kind
/// carus writes.
pub fn folder_kind(dir: &std::path::Path) -> Option<String> {
    let d = dir.display();
    if dir.join(sweep::PLAN_FILE).is_file() {
        return Some(format!("{d} is a sweep's folder: `carus sweep --resume {d}` goes on with it, and each run in it is a run's folder"));
    }
    if dir.join(sanity::PLAN_FILE).is_file() {
        return Some(format!("{d} is the folder of `carus sanity`: `carus sanity --resume {d}` goes on with it"));
    }
    holds_run(dir).then(|| format!("{d} is a run's folder: `carus run --resume {d}` goes on with a stopped run, `carus view {d}` replays it"))
}

/// A `--resume` folder that is not there, or a file given for it, named
/// with what `carus {command} --resume` takes (a folder holding `kept`),
/// and for a file in such a folder, the folder.
pub fn check_resume_dir(dir: &std::path::Path, command: &str, kept: &str) -> anyhow::Result<()> {
    let d = dir.display();
    if dir.is_file() {
        let folder = dir.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
        if folder.join(kept).is_file() {
            anyhow::bail!("{d} is a file; --resume takes its folder: `carus {command} --resume {}`", folder.display());
        }
        anyhow::bail!("{d} is a file; --resume takes the folder that `carus {command}` wrote ({kept} in it)");
    }
    if !dir.exists() {
        anyhow::bail!("{d} does not exist; --resume takes the folder that `carus {command}` wrote ({kept} in it)");
    }
    Ok(())
}

/// Refuses a cube of `n` elements per edge, `per_cell` elements in each of
/// its n^3 cells (1 for H8, 6 for T4), that is larger than the commands
/// build; `even`: only even n are built (the validation cube's), so the
/// largest offered is even.
pub fn check_cube_size(n: usize, per_cell: usize, even: bool) -> anyhow::Result<()> {
    let elements = n.checked_pow(3).and_then(|c| c.checked_mul(per_cell));
    if elements.is_none_or(|e| e > MOST_CUBE_ELEMENTS) {
        let largest = (1..)
            .take_while(|m: &usize| m.pow(3) * per_cell <= MOST_CUBE_ELEMENTS)
            .filter(|m| !even || m.is_multiple_of(2))
            .last()
            .unwrap_or(2);
        crate::bad_argument!(
            "--n {n}: a cube of {n}^3 cells is more than the {MOST_CUBE_ELEMENTS} elements these commands build; \
             use --n {largest} or less"
        );
    }
    Ok(())
}

/// Prints `value` as one JSON object on standard output (CONVENTIONS.md:
/// with `--json`, nothing else goes to standard output). A reader that
/// stops early (`carus run --json | head`) closes the pipe;
/// that is not an error of the run, whose results are already on disk.
pub fn print_json<T: serde::Serialize>(value: &T) -> anyhow::Result<()> {
    use std::io::Write;
    let text = serde_json::to_string_pretty(value)?;
    match writeln!(std::io::stdout().lock(), "{text}") {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// The normal scenario made coarse for the commands' tests: a coarser
/// head, sparser contact samples, a small floor, `end_s` simulated, no VTU.
#[cfg(test)]
pub fn coarse_normal(end_s: f64) -> carus_labour::Scenario {
    let mut s = carus_labour::Scenario::builtin("normal").unwrap();
    s.numerics.head_subdivisions = 3;
    s.contact.sample_spacing_mm = 8.0;
    s.floor.mesh.elements_around = 16;
    s.floor.mesh.elements_across = 3;
    s.numerics.end_time_s = end_s;
    s.output.vtu = false;
    s
}

#[cfg(test)]
mod tests {
    /// --jobs is capped at the runs or the cores, whichever is more (a huge
    /// one would spend its time starting threads), and 0 is refused.
    #[test]
    fn the_runs_threads_are_never_more_than_the_runs() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(super::labour_pool(Some(100_000), 2).unwrap().1, cores.max(2));
        assert_eq!(super::labour_pool(Some(100_000), cores + 3).unwrap().1, cores + 3);
        assert_eq!(super::labour_pool(Some(1), 4).unwrap().1, 1);
        // One run still gets every core for its own parallel passes.
        assert_eq!(super::labour_pool(None, 1).unwrap().1, cores);
        assert!(super::labour_pool(Some(0), 2).err().unwrap().to_string().contains("at least 1"));
    }

    /// A `--resume` folder that is not there, or a file given for it, is
    /// named with what the command takes; a file in a batch's folder gets
    /// that folder.
    #[test]
    fn a_resume_folder_that_is_missing_or_a_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("gone");
        let e = super::check_resume_dir(&missing, "sweep", super::sweep::PLAN_FILE).unwrap_err().to_string();
        assert!(e.contains("does not exist") && e.contains("`carus sweep` wrote (sweep_plan.json in it)"), "{e}");
        std::fs::write(dir.path().join(super::sweep::PLAN_FILE), "{}").unwrap();
        let table = dir.path().join("sweep.csv");
        std::fs::write(&table, "").unwrap();
        let e = super::check_resume_dir(&table, "sweep", super::sweep::PLAN_FILE).unwrap_err().to_string();
        assert!(e.contains(&format!("takes its folder: `carus sweep --resume {}`", dir.path().display())), "{e}");
        let e = super::check_resume_dir(&table, "sanity", super::sanity::PLAN_FILE).unwrap_err().to_string();
        assert!(e.contains("is a file; --resume takes the folder that `carus sanity` wrote"), "{e}");
        assert!(super::check_resume_dir(dir.path(), "sweep", super::sweep::PLAN_FILE).is_ok());
    }

    /// A folder given to the wrong command is named for what it is, with
    /// the command that takes it.
    #[test]
    fn a_folder_is_named_for_what_carus_wrote_in_it() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(super::folder_kind(dir.path()), None);
        std::fs::write(dir.path().join(carus_labour::output::SCENARIO_FILE), "").unwrap();
        assert_eq!(super::folder_kind(dir.path()), None, "a scenario alone is no run");
        std::fs::write(dir.path().join(carus_labour::output::CHECKPOINT_FILE), "{}").unwrap();
        assert!(super::folder_kind(dir.path()).unwrap().contains("is a run's folder: `carus run --resume"));
        std::fs::write(dir.path().join(super::sanity::PLAN_FILE), "{}").unwrap();
        assert!(super::folder_kind(dir.path()).unwrap().contains("`carus sanity --resume"));
        std::fs::write(dir.path().join(super::sweep::PLAN_FILE), "{}").unwrap();
        assert!(super::folder_kind(dir.path()).unwrap().contains("is a sweep's folder: `carus sweep --resume"));
    }

    /// A cube too large to allocate is refused with the largest that is
    /// built, before anything is allocated; the usual sizes pass.
    #[test]
    fn a_cube_too_large_is_refused_with_the_largest_size() {
        super::check_cube_size(20, 6, false).unwrap();
        super::check_cube_size(271, 1, false).unwrap();
        let e = super::check_cube_size(272, 1, false).unwrap_err().to_string();
        assert!(e.contains("--n 272") && e.contains("use --n 271 or less"), "{e}");
        let e = super::check_cube_size(100_000, 6, false).unwrap_err().to_string();
        assert!(e.contains("use --n 149 or less"), "{e}");
        // The validation cube, even sizes only, is offered an even one.
        let e = super::check_cube_size(100_000, 6, true).unwrap_err().to_string();
        assert!(e.contains("use --n 148 or less"), "{e}");
        assert!(super::check_cube_size(usize::MAX, 1, false).is_err());
    }

    /// A file where the out folder should be is named with the fix, by
    /// every command that writes a folder.
    #[test]
    fn a_file_in_place_of_the_out_folder_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("afile");
        std::fs::write(&file, "mine").unwrap();
        let e = super::create_out_folder(&file, "--screenshot").unwrap_err().to_string();
        assert!(e.ends_with("afile is a file, not a folder; choose another --screenshot"), "{e}");
        let e = super::run::choose_out_dir(Some(&file), "x", true).err().unwrap().to_string();
        assert!(e.contains("is a file, not a folder"), "{e}");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
        super::create_out_folder(&dir.path().join("a/b"), "--out").unwrap();
        assert!(dir.path().join("a/b").is_dir());
    }

    /// A folder that cannot be made, or a picture path that is a folder,
    /// is named with what to do, not the OS's words alone; a folder given
    /// for a picture is refused before anything is drawn.
    #[test]
    fn a_place_that_cannot_be_written_says_what_to_do() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("afile");
        std::fs::write(&file, "mine").unwrap();
        let e = super::create_out_folder(&file.join("x"), "--out").unwrap_err().to_string();
        assert!(e.contains("cannot create the folder") && e.contains("choose another --out"), "{e}");
        let missing = std::io::Error::from(std::io::ErrorKind::NotFound);
        assert!(super::io_fix(&missing, "--out").contains("a system folder such as /proc"), "{missing}");
        let e = super::check_picture_path(dir.path(), "--out").unwrap_err();
        assert!(e.downcast_ref::<super::BadArgument>().is_some(), "{e}");
        let e = e.to_string();
        assert!(e.contains("is a folder; give the picture's file name, e.g. --out") && e.contains("picture.png"), "{e}");
        super::check_picture_path(&dir.path().join("new.png"), "--out").unwrap();
        let picture = carus_render::Image::filled(2, 2, [0, 0, 0, 255]);
        let e = super::save_picture(&picture, dir.path(), "--picture").unwrap_err().to_string();
        assert!(e.contains("cannot write") && e.contains("--picture"), "{e}");
    }
}
