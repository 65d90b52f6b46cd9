//! `carus view RUN [--at T] [--landmarks] [--forces] [--screenshot
//! FILE.png]`, `carus view RUN --at T --picture FILE.png`: a run replayed
//! in a window (crate carus-view), or one of its frames drawn to a picture
//! without one. A run still going is shown from its last checkpoint, and
//! the window follows it as it writes more.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use anyhow::Context;
use carus_analysis::{DetectorReport, PoseSample};
use carus_labour::loads::LoadSample;
use carus_labour::output::{read_checkpoint, run_ending, CHECKPOINT_FILE, RUN_FILE};
use carus_labour::record::FloorAtMoment;
use carus_labour::sim::FloorSample;
use carus_labour::{Scenario, Scene};
use carus_view::{Follow, Layers, Replay};

use super::render::{pelvis_markers, ViewName, HEAD_AMONG_PELVIS_RGB, HEAD_MARKER_M};
use super::run::{read_record, run_ended, run_title, scene_with_floors};
use super::{print_json, Status};

#[derive(clap::Args)]
pub struct ViewArgs {
    /// A run folder, as `carus run` writes it.
    pub run: PathBuf,
    /// The time shown first, s (default 0, or the newest for a run not over); with --picture, the frame drawn.
    #[arg(long, allow_negative_numbers = true)]
    pub at: Option<f64>,
    /// The PNG file the frame at --at is drawn to, without opening a window (needs --at).
    #[arg(long, requires = "at")]
    pub picture: Option<PathBuf>,
    /// The view the picture is drawn from, or the window first shows.
    #[arg(long, value_enum, default_value = "lateral")]
    pub view: ViewName,
    /// Open the window, save a PNG of it once drawn, and close it.
    #[arg(long, conflicts_with = "picture")]
    pub screenshot: Option<PathBuf>,
    /// With --picture: width and height of the picture, px (the window's --screenshot is the window's size).
    #[arg(long, requires = "picture", num_args = 2, default_values = ["800", "600"], value_names = ["WIDTH", "HEIGHT"], value_parser = clap::value_parser!(u32).range(1..))]
    pub size: Vec<u32>,
    /// Show the pelvis's landmarks, obstetric planes and axis, and the head's landmarks (a check box in the window).
    #[arg(long)]
    pub landmarks: bool,
    /// Show the forces on the fetus as arrows: each part of the canal, the
    /// expulsion and any guide (a check box in the window).
    #[arg(long)]
    pub forces: bool,
    /// With --picture: print one JSON object (the picture, and the frame's time, station, theta, phi, movements under way and, with --forces, the forces) on standard output.
    #[arg(long, requires = "picture")]
    pub json: bool,
}

pub fn run(args: &ViewArgs) -> anyhow::Result<Status> {
    let shown = RunShown::read(&args.run)?;
    let scene = RunScene::build(&shown.scenario)
        .with_context(|| format!("the scenario kept in {}", shown.source.display()))?;
    let replay = shown.replay(&scene).with_context(|| args.run.display().to_string())?;
    if args.forces && !replay.layers_available().forces {
        anyhow::bail!(
            "--forces: {} records no loads (a run written by a carus from before they were recorded); \
             run its scenario again to draw its forces, or leave out --forces",
            args.run.join(RUN_FILE).display()
        );
    }
    let layers = Layers { markers: args.landmarks, forces: args.forces };
    for (flag, path) in [("--picture", &args.picture), ("--screenshot", &args.screenshot)] {
        if let Some(path) = path.as_ref().filter(|p| !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))) {
            crate::bad_argument!("{flag} {}: the picture is written as a PNG; name the file *.png", path.display());
        }
        if let Some(path) = path {
            super::check_picture_path(path, flag)?;
        }
    }
    let end = replay.duration_s();
    // A run not over is followed: without --at it opens at its newest time.
    let ended = run_ended(&args.run);
    let at = args.at.unwrap_or(if ended { 0.0 } else { end });
    if !(at.is_finite() && (0.0..=end).contains(&at)) {
        crate::bad_argument!("--at {}: the run was recorded from 0 to {end:.2} s; give a time in that range", carus_io::shown_number(at));
    }
    let Some(path) = &args.picture else {
        // Made before the window opens, as `carus render` makes its folder.
        if let Some(folder) = args.screenshot.as_ref().and_then(|p| p.parent()).filter(|f| !f.as_os_str().is_empty()) {
            super::create_out_folder(folder, "--screenshot")?;
        }
        let follow = (!ended).then(|| follow_in_background(args.run.clone(), scene));
        carus_view::open(replay, at, args.view.into(), layers, args.screenshot.clone(), follow)?;
        return Ok(Status::Success);
    };
    if let Some(folder) = path.parent().filter(|f| !f.as_os_str().is_empty()) {
        super::create_out_folder(folder, "--picture")?;
    }
    let [width, height] = [args.size[0], args.size[1]];
    let picture = replay.picture(at, &replay.standard_camera(args.view.into()), layers, width, height)?;
    super::save_picture(&picture, path, "--picture")?;
    let k = replay.sample_at(at);
    if args.json {
        print_json(&picture_json(&replay, k, path, args))?;
        return Ok(Status::Success);
    }
    println!("{} ({width} x {height}): {}", path.display(), replay.readout(k).join(", "));
    if args.forces {
        println!("forces: {}", replay.force_readout(k).join(", "));
    }
    Ok(Status::Success)
}

/// `carus view --picture --json`: the picture drawn and what its frame
/// shows, the forces largest first (with --forces).
fn picture_json(replay: &Replay, k: usize, path: &Path, args: &ViewArgs) -> serde_json::Value {
    let state = replay.state(k);
    let mut json = serde_json::json!({
        "picture": path.display().to_string(),
        "width": args.size[0],
        "height": args.size[1],
        "view": carus_render::View::from(args.view).name(),
        "time_s": state.time_s,
        "station_mm": state.station_mm,
        "theta_deg": state.theta_deg,
        "occiput_position": carus_analysis::occiput_position(state.theta_deg),
        "phi_deg": state.phi_deg,
        "head_engaged": state.head_engaged,
        "head_delivered": state.head_delivered,
        "movements_under_way": state.under_way,
    });
    if args.forces {
        let forces: Vec<serde_json::Value> = carus_view::forces::largest_first(replay.arrows(k))
            .iter()
            .map(|a| serde_json::json!({ "on": a.label, "force_n": a.force_n.to_array(), "magnitude_n": a.force_n.length() }))
            .collect();
        json["forces"] = forces.into();
    }
    json
}

/// What the viewer shows of a run folder: its record once the run has
/// written one, or while the run is still going, its last checkpoint.
struct RunShown {
    scenario: Scenario,
    samples: Vec<PoseSample>,
    /// The record's; a run in progress is read by the detector as it stands.
    detector: Option<DetectorReport>,
    loads: Vec<LoadSample>,
    /// The floor's states kept: the key moments' and the VTU frames'.
    floors: Vec<FloorAtMoment>,
    /// When a floor element first had a corner turned inside out, if one did:
    /// the colour scale is read from the floor before it (the report's
    /// `floor_untrusted_from_s`).
    floor_untrusted_from_s: Option<f64>,
    /// Read from the checkpoint: the run has not written its record.
    in_progress: bool,
    /// The file the samples were read from, for messages.
    source: PathBuf,
}

/// Frames a run wrote but that cannot be read now (deleted, damaged):
/// the replay goes on without them, and says so.
fn warn_unreadable_floor_frames(unreadable: &[PathBuf]) {
    if let Some(first) = unreadable.first() {
        eprintln!(
            "warning: {} of the floor's frames cannot be read ({} first); the floor is shown at the \
             nearest state the run kept: run the scenario again for the whole series",
            unreadable.len(),
            first.display()
        );
    }
}

impl RunShown {
    fn read(dir: &Path) -> anyhow::Result<RunShown> {
        if !dir.join(RUN_FILE).exists() && !dir.join(CHECKPOINT_FILE).exists() {
            if let Some(kind) = super::folder_kind(dir) {
                anyhow::bail!("{} holds no run to show: {kind}", dir.display());
            }
            let d = dir.display();
            // A scenario given where its run belongs: run it first.
            let builtin = carus_labour::BUILTINS.iter().any(|(name, _)| Path::new(name) == dir);
            // A file of a run (its run.json, its scenario.toml): its folder.
            if let Some(run) = dir.parent().filter(|f| dir.is_file() && super::holds_run(f)) {
                anyhow::bail!("{d} is a file of the run in {0}: `carus view {0}` replays it", run.display());
            }
            if dir.is_file() || (builtin && !dir.exists()) {
                let what = if dir.is_file() { "a file" } else { "a built-in scenario" };
                anyhow::bail!(
                    "{d} is {what}, not a run's folder: `carus view` replays a run; run the scenario first with \
                     `carus run {d} --out DIR`, then `carus view DIR`"
                );
            }
            if !dir.exists() {
                anyhow::bail!(
                    "there is no folder {d}: `carus view` replays the folder of a run (`carus run NAME --out DIR` \
                     makes one; without --out, runs/NAME-N)"
                );
            }
            anyhow::bail!(
                "{} holds no run to show: neither {RUN_FILE} (written when a run ends) nor {CHECKPOINT_FILE} \
                 (written at each checkpoint while it goes); give a folder that `carus run` wrote, or wait \
                 for a run just started to reach its first checkpoint",
                dir.display()
            );
        }
        if !checkpoint_is_newer(dir) {
            return RunShown::from_record(dir);
        }
        let checkpoint = read_checkpoint(dir)?;
        // A folder copied without its files' times can date the checkpoint
        // after a record that holds as much: the record is then the run.
        let checkpoint_s = checkpoint.state.samples.last().map_or(0.0, |s| s.time_s);
        if run_ending(dir).is_some_and(|e| e.simulated_s >= checkpoint_s) {
            return RunShown::from_record(dir);
        }
        // A run without a floor writes no floor frames at its frame times.
        let (floors, unreadable) = match checkpoint.state.floor {
            Some(_) => carus_labour::floor_frames_at(dir, &checkpoint.frame_times),
            None => Default::default(),
        };
        warn_unreadable_floor_frames(&unreadable);
        Ok(RunShown {
            scenario: checkpoint.scenario(dir)?,
            floor_untrusted_from_s: FloorSample::first_inverted_s(&checkpoint.state.floor_samples),
            floors,
            samples: checkpoint.state.samples,
            detector: None,
            loads: checkpoint.state.loads,
            in_progress: true,
            source: dir.join(CHECKPOINT_FILE),
        })
    }

    fn from_record(dir: &Path) -> anyhow::Result<RunShown> {
        let record = read_record(dir)?;
        let (mut floors, unreadable) = carus_labour::floor_frames(dir, &record);
        warn_unreadable_floor_frames(&unreadable);
        floors.extend(record.key_moments.iter().filter_map(|m| m.floor.clone()));
        Ok(RunShown {
            scenario: record.scenario,
            samples: record.history.samples,
            detector: record.detector,
            loads: record.loads,
            floor_untrusted_from_s: FloorSample::first_inverted_s(&record.floor),
            floors,
            in_progress: false,
            source: dir.join(RUN_FILE),
        })
    }

    /// The replay of the run in `run_scene`, built from its scenario.
    fn replay(self, run_scene: &RunScene) -> anyhow::Result<Replay> {
        let scene = &run_scene.scene;
        let history = carus_labour::run::history_of(scene, self.samples);
        // A damaged record (edited, or cut short on disk) is named, as
        // `carus detect` names it, rather than drawn wrong.
        match history.validate() {
            Ok(()) | Err(carus_analysis::history::HistoryError::TooFewSamples { .. }) => {}
            Err(e) => anyhow::bail!(
                "{}: the pose history is damaged: {e}; run the scenario again, or a stopped run \
                 with `carus run --resume` from its checkpoint",
                self.source.display()
            ),
        }
        let detector = self.detector.or_else(|| (history.samples.len() >= 2).then(|| carus_analysis::detect(&history).ok()).flatten());
        let mut title = run_title(&self.scenario);
        if self.in_progress {
            title.push_str(" - in progress, from its last checkpoint");
        }
        let floors = scene_with_floors(scene, self.floors.iter().collect());
        let replay = Replay::new(title, floors, history, detector.as_ref())?;
        let replay = match self.floor_untrusted_from_s {
            Some(t_s) => replay.with_stretch_scale_before(t_s),
            None => replay,
        };
        // A run written before the loads were recorded has none to draw.
        let replay = match self.loads.is_empty() {
            true => replay,
            false => replay.with_forces(self.loads, scene.pivot_in_head, scene.expulsion_at_pivot())?,
        };
        let head_landmarks = scene.head_landmarks.named().iter().map(|(name, p)| (name.to_string(), *p)).collect();
        Ok(replay
            .with_markers(run_scene.pelvis_markers.clone())
            .with_head_markers(head_landmarks, HEAD_MARKER_M, HEAD_AMONG_PELVIS_RGB))
    }
}

/// A run's scene, and what of it every replay of the run draws the same:
/// built once, however often a followed run is read again.
struct RunScene {
    scene: Scene,
    pelvis_markers: Vec<carus_render::RenderMesh>,
}

impl RunScene {
    fn build(scenario: &Scenario) -> anyhow::Result<RunScene> {
        let scene = Scene::build(scenario)?;
        Ok(RunScene { pelvis_markers: pelvis_markers(&scene.pelvis), scene })
    }
}

/// Whether the run in `dir` may hold more in its checkpoint than in its
/// record (a run still going, or killed before it wrote its record): the
/// checkpoint is newer than the record, or there is no record, and the
/// run is not over (`RunShown::read` then compares what the two hold).
fn checkpoint_is_newer(dir: &Path) -> bool {
    let newer = match (modified(&dir.join(CHECKPOINT_FILE)), modified(&dir.join(RUN_FILE))) {
        (Some(checkpoint), Some(record)) => checkpoint > record,
        (Some(_), None) => true,
        _ => false,
    };
    newer && !run_ended(dir)
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The window's follower of a run not over (going, or stopped part way and
/// perhaps resumed): each call reads the run again if it wrote a
/// checkpoint or its record since the last call read it, and says whether
/// the run may still go on.
fn follow(dir: PathBuf, scene: RunScene) -> impl FnMut() -> Option<(Replay, bool)> + Send {
    let seen = |dir: &Path| (modified(&dir.join(CHECKPOINT_FILE)), modified(&dir.join(RUN_FILE)));
    let mut last = seen(&dir);
    move || {
        let now = seen(&dir);
        if now == last {
            return None;
        }
        let replay = RunShown::read(&dir).and_then(|shown| shown.replay(&scene)).ok()?;
        // Only once read: a write under way is read again at the next call.
        last = now;
        Some((replay, !run_ended(&dir)))
    }
}

/// `follow` on a thread of its own, asking once a second, so that reading
/// a checkpoint (megabytes of JSON, the detector, the replay's surfaces)
/// never holds up the window; the window takes what it has read.
fn follow_in_background(dir: PathBuf, scene: RunScene) -> Follow {
    let (sender, read) = std::sync::mpsc::channel();
    let mut more = follow(dir, scene);
    std::thread::spawn(move || loop {
        if let Some((replay, goes_on)) = more() {
            // The window closed: nothing is waiting for more.
            if sender.send((replay, goes_on)).is_err() || !goes_on {
                return;
            }
        }
        std::thread::sleep(std::time::Duration::from_secs(1));
    });
    Box::new(move || read.try_iter().last())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(run: PathBuf, at: f64, picture: PathBuf) -> ViewArgs {
        ViewArgs { run, at: Some(at), picture: Some(picture), screenshot: None, view: ViewName::Inferior, size: vec![120, 90], landmarks: true, forces: true, json: false }
    }

    /// A run's frame is drawn to a PNG of the size asked, with the floor
    /// from the run's VTU frames; a time outside the run, a picture that
    /// is not a PNG and a folder without a run are refused with the fix.
    /// Needs a GPU or Mesa's lavapipe (`.ci/run` installs it).
    #[test]
    fn a_frame_of_a_run_is_drawn_to_a_picture() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = crate::commands::coarse_normal(0.3);
        s.output.vtu = true;
        s.output.vtu_every_s = 0.1;
        let record = carus_labour::run(&s, dir.path(), &carus_labour::RunOptions::default(), &mut carus_labour::SilentObserver).unwrap();
        assert_eq!(carus_labour::floor_frames(dir.path(), &record).0.len(), 4);
        // A damaged frame is left out and named.
        let frame = dir.path().join("frames/floor_0002.vtu");
        let saved = std::fs::read(&frame).unwrap();
        std::fs::write(&frame, &saved[..300]).unwrap();
        let (frames, unreadable) = carus_labour::floor_frames(dir.path(), &record);
        assert_eq!((frames.len(), unreadable), (3, vec![frame.clone()]));
        // So it is in a run still going, whose frames a checkpoint lists.
        let (frames, unreadable) = carus_labour::floor_frames_at(dir.path(), &[0.0, 0.1, 0.2, 0.3]);
        assert_eq!((frames.len(), unreadable), (3, vec![frame.clone()]));
        std::fs::write(&frame, saved).unwrap();
        let png = dir.path().join("frame.png");
        run(&args(dir.path().to_path_buf(), 0.2, png.clone())).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"));
        // Width and height in the PNG header.
        assert_eq!((&bytes[16..20], &bytes[20..24]), (&120u32.to_be_bytes()[..], &90u32.to_be_bytes()[..]));
        // With --json, the same frame as numbers: the detector's series at
        // the sample drawn, and the forces largest first.
        let shown = RunShown::read(dir.path()).unwrap();
        let scene = RunScene::build(&shown.scenario).unwrap();
        let replay = shown.replay(&scene).unwrap();
        let k = replay.sample_at(0.2);
        let json = picture_json(&replay, k, &png, &args(dir.path().to_path_buf(), 0.2, png.clone()));
        let series = &record.detector.as_ref().unwrap().series;
        assert_eq!(json["time_s"].as_f64(), Some(series.time_s[k]));
        assert!(series.time_s[k] <= 0.2 && 0.2 - series.time_s[k] < s.output.every_s);
        for (key, value) in [("station_mm", series.station_mm[k]), ("theta_deg", series.theta_deg[k]), ("phi_deg", series.phi_deg[k])] {
            assert_eq!(json[key].as_f64(), Some(value), "{key}");
        }
        assert_eq!((json["view"].as_str(), json["width"].as_u64(), json["head_delivered"].as_bool()), (Some("inferior"), Some(120), Some(false)));
        let forces = json["forces"].as_array().unwrap();
        assert_eq!(forces.len(), replay.arrows(k).len());
        let magnitudes: Vec<f64> = forces.iter().map(|f| f["magnitude_n"].as_f64().unwrap()).collect();
        assert!(magnitudes.windows(2).all(|w| w[0] >= w[1]), "{magnitudes:?}");

        let refused = |a: ViewArgs| format!("{:#}", run(&a).expect_err("refused"));
        let e = refused(args(dir.path().to_path_buf(), 5.0, png.clone()));
        assert!(e.contains("--at 5") && e.contains("from 0 to 0.30 s"), "{e}");
        let e = refused(args(dir.path().to_path_buf(), -1e300, png.clone()));
        assert!(e.contains("--at -1e300:"), "{e}");
        // A picture's folder is made, as `carus render` makes its own; a
        // file where the folder goes is refused before a window opens.
        let nested = dir.path().join("pictures/t0.1/inferior.png");
        assert!(matches!(run(&args(dir.path().to_path_buf(), 0.1, nested.clone())).unwrap(), Status::Success));
        assert!(nested.is_file());
        std::fs::write(dir.path().join("a-file"), "").unwrap();
        let mut window = args(dir.path().to_path_buf(), 0.1, png.clone());
        (window.picture, window.screenshot) = (None, Some(dir.path().join("a-file/w.png")));
        let e = refused(window);
        assert!(e.contains("a-file is a file, not a folder"), "{e}");
        let e = refused(args(dir.path().to_path_buf(), 0.1, dir.path().join("frame.jpg")));
        assert!(e.contains("*.png"), "{e}");
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        let e = refused(args(empty, 0.1, png.clone()));
        assert!(e.contains("holds no run to show") && e.contains("run.json") && e.contains("checkpoint.json"), "{e}");
        let e = refused(args(dir.path().join("nothing"), 0.1, png.clone()));
        assert!(e.contains("there is no folder") && e.contains("nothing"), "{e}");
        let e = refused(args(PathBuf::from("textbook"), 0.1, png.clone()));
        assert!(e.contains("textbook is a built-in scenario, not a run's folder") && e.contains("`carus run textbook --out DIR`"), "{e}");
        let elsewhere = tempfile::tempdir().unwrap();
        let notes = elsewhere.path().join("notes.txt");
        std::fs::write(&notes, "").unwrap();
        let e = refused(args(notes, 0.1, png.clone()));
        assert!(e.contains("notes.txt is a file, not a run's folder"), "{e}");
        let e = refused(args(dir.path().join(RUN_FILE), 0.1, png.clone()));
        assert!(e.contains(&format!("is a file of the run in {0}: `carus view {0}` replays it", dir.path().display())), "{e}");
        // A record cut short is named, with the way to write it again from
        // the run's checkpoint; one damaged after the run (a sample out of
        // time order) is named, not drawn.
        let whole = serde_json::to_string(&record).unwrap();
        std::fs::write(dir.path().join(RUN_FILE), &whole[..whole.len() / 2]).unwrap();
        let e = crate::error_text(&RunShown::read(dir.path()).err().unwrap());
        assert!(e.contains("run.json is damaged (EOF while parsing") && e.contains(&format!("; `carus run --resume {}` writes it again from the run's last checkpoint", dir.path().display())), "{e}");
        let mut damaged = record;
        damaged.history.samples.swap(3, 4);
        std::fs::write(dir.path().join(RUN_FILE), serde_json::to_string(&damaged).unwrap()).unwrap();
        let e = refused(args(dir.path().to_path_buf(), 0.1, png));
        assert!(e.contains("run.json") && e.contains("pose history is damaged") && e.contains("sample 4"), "{e}");
    }

    /// A run still going is shown from its checkpoint, and followed: the
    /// follower gives nothing until the run writes more, then the run as
    /// it now stands, and once the run has written its record, that.
    #[test]
    fn a_run_still_going_is_followed_from_its_checkpoints() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = crate::commands::coarse_normal(0.3);
        s.numerics.checkpoint_every_s = 0.05;
        s.output.vtu = true;
        s.output.vtu_every_s = 0.05;
        let stopped_at = |t| carus_labour::RunOptions { stop: None, stop_at_s: Some(t) };
        carus_labour::run(&s, dir.path(), &stopped_at(0.1), &mut carus_labour::SilentObserver).unwrap();
        // A run killed before it wrote its record, or still going.
        std::fs::remove_file(dir.path().join(RUN_FILE)).unwrap();
        assert!(checkpoint_is_newer(dir.path()));
        let shown = RunShown::read(dir.path()).unwrap();
        assert!(shown.in_progress && shown.detector.is_none());
        assert_eq!(shown.floors.len(), 3, "the floor frames at 0, 0.05 and 0.1 s");
        let scene = RunScene::build(&shown.scenario).unwrap();
        let replay = shown.replay(&scene).unwrap();
        assert!((replay.duration_s() - 0.1).abs() < 1e-9 && replay.title.ends_with("in progress, from its last checkpoint"));
        assert!(replay.layers_available().forces);
        // A picture of it, from the checkpoint.
        let png = dir.path().join("going.png");
        run(&args(dir.path().to_path_buf(), 0.05, png.clone())).unwrap();
        assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));

        let mut more = follow(dir.path().to_path_buf(), scene);
        assert!(more().is_none(), "nothing new was written");
        carus_labour::resume(dir.path(), &stopped_at(0.2), &mut carus_labour::SilentObserver).unwrap();
        let (replay, goes_on) = more().expect("the run wrote more");
        // Stopped part way again: it may be resumed, so it is still followed.
        assert!((replay.duration_s() - 0.2).abs() < 1e-9 && goes_on, "{}", replay.duration_s());
        assert!(!replay.title.contains("in progress"), "the run wrote its record: {}", replay.title);
        assert!(more().is_none());
        assert!(!checkpoint_is_newer(dir.path()));
        // A copy that dates its checkpoint after its record shows the
        // record, which holds as much. (Dated a second on: a rewrite within
        // the file system's clock tick would keep the same time.)
        let record_time = modified(&dir.path().join(RUN_FILE)).unwrap();
        let checkpoint = std::fs::File::options().write(true).open(dir.path().join(CHECKPOINT_FILE)).unwrap();
        checkpoint.set_modified(record_time + std::time::Duration::from_secs(1)).unwrap();
        assert!(checkpoint_is_newer(dir.path()) && !RunShown::read(dir.path()).unwrap().in_progress);
        // Run to its end, it is over.
        carus_labour::resume(dir.path(), &carus_labour::RunOptions::default(), &mut carus_labour::SilentObserver).unwrap();
        let (replay, goes_on) = more().expect("the run wrote more");
        assert!((replay.duration_s() - 0.3).abs() < 1e-9 && !goes_on, "{}", replay.duration_s());
    }

    #[test]
    fn a_time_and_a_picture_go_together() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            view: ViewArgs,
        }
        use clap::Parser;
        assert_eq!(Cli::try_parse_from(["view", "runs/x", "--at", "1"]).unwrap().view.at, Some(1.0));
        assert!(Cli::try_parse_from(["view", "runs/x", "--picture", "a.png"]).is_err());
        assert!(Cli::try_parse_from(["view", "runs/x", "--at", "1", "--picture", "a.png", "--screenshot", "b.png"]).is_err());
        assert!(Cli::try_parse_from(["view", "runs/x", "--size", "10", "10"]).is_err());
        assert!(Cli::try_parse_from(["view", "runs/x", "--json"]).is_err());
        assert!(Cli::try_parse_from(["view", "runs/x", "--at", "1", "--picture", "a.png", "--json"]).unwrap().view.json);
        assert_eq!(Cli::try_parse_from(["view", "runs/x", "--at", "-1"]).unwrap().view.at, Some(-1.0));
        let both = Cli::try_parse_from(["view", "runs/x", "--at", "1", "--picture", "a.png"]).unwrap();
        assert_eq!((both.view.at, both.view.size.as_slice(), both.view.view), (Some(1.0), &[800, 600][..], ViewName::Lateral));
        let bare = Cli::try_parse_from(["view", "runs/x"]).unwrap().view;
        assert!(bare.picture.is_none() && !bare.landmarks && !bare.forces);
        let layers = Cli::try_parse_from(["view", "runs/x", "--landmarks", "--forces"]).unwrap().view;
        assert!(layers.landmarks && layers.forces);
    }
}
