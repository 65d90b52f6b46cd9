//! `carus view RUN [--at T] [--landmarks] [--forces] [--screenshot
//! FILE.png]`, `carus view RUN --at T --picture FILE.png`: a run replayed
//! in a window (crate carus-view), or one of its frames drawn to a picture
//! without one.

use std::path::PathBuf;

use carus_view::{Layers, Replay};

use super::render::{pelvis_markers, ViewName};
use super::run::{read_record, report_scene, run_title};
use super::Status;

#[derive(clap::Args)]
pub struct ViewArgs {
    /// A run folder, as `carus run` writes it.
    pub run: PathBuf,
    /// The time shown first, s; with --picture, the frame drawn.
    #[arg(long, allow_negative_numbers = true)]
    pub at: Option<f64>,
    /// The PNG file the frame at --at is drawn to.
    #[arg(long, requires = "at")]
    pub picture: Option<PathBuf>,
    /// The view the picture is drawn from, or the window first shows.
    #[arg(long, value_enum, default_value = "lateral")]
    pub view: ViewName,
    /// Open the window, save a PNG of it once drawn, and close it.
    #[arg(long, conflicts_with = "picture")]
    pub screenshot: Option<PathBuf>,
    /// Width and height of the picture, px.
    #[arg(long, requires = "picture", num_args = 2, default_values = ["800", "600"], value_names = ["WIDTH", "HEIGHT"])]
    pub size: Vec<u32>,
    /// Show the pelvis's landmarks, obstetric planes and axis (a check box in the window).
    #[arg(long)]
    pub landmarks: bool,
    /// Show the forces on the fetus as arrows: each part of the canal, the
    /// expulsion and any guide (a check box in the window).
    #[arg(long)]
    pub forces: bool,
}

pub fn run(args: &ViewArgs) -> anyhow::Result<Status> {
    let record = read_record(&args.run)?;
    // The floor at every VTU frame the run wrote, besides its key moments'.
    let frames = carus_labour::floor_frames(&args.run, &record);
    let scene = carus_labour::Scene::build(&record.scenario)?;
    let expulsion_at_pivot = scene.trunk.is_none() || record.scenario.expulsion.acts_on == carus_labour::scenario::ActsOn::Pivot;
    let replay = Replay::new(run_title(&record), report_scene(&record, &scene, &frames), record.history.clone(), record.detector.as_ref())
        .and_then(|r| r.with_forces(record.loads.clone(), scene.pivot_in_head, expulsion_at_pivot))
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.run.display()))?
        .with_markers(pelvis_markers(&scene.pelvis));
    let layers = Layers { markers: args.landmarks, forces: args.forces };
    for (flag, path) in [("--picture", &args.picture), ("--screenshot", &args.screenshot)] {
        if let Some(path) = path.as_ref().filter(|p| !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))) {
            anyhow::bail!("{flag} {}: the picture is written as a PNG; name the file *.png", path.display());
        }
    }
    let end = replay.duration_s();
    let at = args.at.unwrap_or(0.0);
    if !(at.is_finite() && (0.0..=end).contains(&at)) {
        let shown = if at.abs() < 1e6 { at.to_string() } else { format!("{at:e}") };
        anyhow::bail!("--at {shown}: the run was recorded from 0 to {end:.2} s; give a time in that range");
    }
    let Some(path) = &args.picture else {
        if let Some(folder) = args.screenshot.as_ref().and_then(|p| p.parent()).filter(|f| !f.as_os_str().is_empty()) {
            anyhow::ensure!(folder.is_dir(), "--screenshot: the folder {} does not exist; make it first", folder.display());
        }
        carus_view::open(replay, at, args.view.into(), layers, args.screenshot.clone())?;
        return Ok(Status::Success);
    };
    let [width, height] = [args.size[0], args.size[1]];
    let picture = replay.picture(at, &replay.standard_camera(args.view.into()), layers, width, height)?;
    picture.save_png(path)?;
    let k = replay.sample_at(at);
    println!("{} ({width} x {height}): {}", path.display(), replay.readout(k).join(", "));
    if args.forces {
        println!("forces: {}", replay.force_readout(k).join(", "));
    }
    Ok(Status::Success)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(run: PathBuf, at: f64, picture: PathBuf) -> ViewArgs {
        ViewArgs { run, at: Some(at), picture: Some(picture), screenshot: None, view: ViewName::Inferior, size: vec![120, 90], landmarks: true, forces: true }
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
        assert_eq!(carus_labour::floor_frames(dir.path(), &record).len(), 4);
        let png = dir.path().join("frame.png");
        run(&args(dir.path().to_path_buf(), 0.2, png.clone())).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"));
        // Width and height in the PNG header.
        assert_eq!((&bytes[16..20], &bytes[20..24]), (&120u32.to_be_bytes()[..], &90u32.to_be_bytes()[..]));

        let refused = |a: ViewArgs| format!("{:#}", run(&a).err().expect("refused"));
        let e = refused(args(dir.path().to_path_buf(), 5.0, png.clone()));
        assert!(e.contains("--at 5") && e.contains("from 0 to 0.30 s"), "{e}");
        let e = refused(args(dir.path().to_path_buf(), -1e300, png.clone()));
        assert!(e.contains("--at -1e300:"), "{e}");
        let mut window = args(dir.path().to_path_buf(), 0.1, png.clone());
        (window.picture, window.screenshot) = (None, Some(dir.path().join("no-such-folder/w.png")));
        let e = refused(window);
        assert!(e.contains("no-such-folder") && e.contains("does not exist"), "{e}");
        let e = refused(args(dir.path().to_path_buf(), 0.1, dir.path().join("frame.jpg")));
        assert!(e.contains("*.png"), "{e}");
        let e = refused(args(dir.path().join("nothing"), 0.1, png));
        assert!(e.contains("run.json"), "{e}");
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
        assert_eq!(Cli::try_parse_from(["view", "runs/x", "--at", "-1"]).unwrap().view.at, Some(-1.0));
        let both = Cli::try_parse_from(["view", "runs/x", "--at", "1", "--picture", "a.png"]).unwrap();
        assert_eq!((both.view.at, both.view.size.as_slice(), both.view.view), (Some(1.0), &[800, 600][..], ViewName::Lateral));
        let bare = Cli::try_parse_from(["view", "runs/x"]).unwrap().view;
        assert!(bare.picture.is_none() && !bare.landmarks && !bare.forces);
        let layers = Cli::try_parse_from(["view", "runs/x", "--landmarks", "--forces"]).unwrap().view;
        assert!(layers.landmarks && layers.forces);
    }
}
