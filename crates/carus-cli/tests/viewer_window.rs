//! The viewer's window opened for real on a virtual X display (Xvfb) with
//! Mesa's lavapipe: `carus view RUN --screenshot FILE` draws a short run,
//! saves a picture of its window and closes. Needs `Xvfb` (Debian package
//! xvfb; `.ci/run` installs it), as the GPU tests need lavapipe.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An Xvfb server, stopped when dropped.
struct VirtualDisplay {
    server: Child,
    number: u32,
    name: String,
}

impl Drop for VirtualDisplay {
    /// Asks the server to end (SIGTERM, so that it removes its lock and
    /// socket), and removes them itself if it could not.
    fn drop(&mut self) {
        // SAFETY: a plain signal to the child this test started.
        unsafe { libc::kill(self.server.id() as libc::pid_t, libc::SIGTERM) };
        let _ = self.server.wait();
        let _ = std::fs::remove_file(format!("/tmp/.X{}-lock", self.number));
        let _ = std::fs::remove_file(format!("/tmp/.X11-unix/X{}", self.number));
    }
}

/// Starts Xvfb on the first free display from :90 and waits for its socket.
fn virtual_display() -> VirtualDisplay {
    let number = (90..190)
        .find(|n| !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() && !Path::new(&format!("/tmp/.X{n}-lock")).exists())
        .expect("a free X display number");
    let name = format!(":{number}");
    let server = Command::new("Xvfb")
        .args([name.as_str(), "-screen", "0", "1280x900x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| {
            panic!("cannot start Xvfb ({e}): this test opens the viewer's window on a virtual display; install it with `apt-get install xvfb` (.ci/run does)")
        });
    let mut display = VirtualDisplay { server, number, name };
    let socket = PathBuf::from(format!("/tmp/.X11-unix/X{number}"));
    let started = Instant::now();
    while !socket.exists() {
        if let Some(status) = display.server.try_wait().unwrap() {
            panic!("Xvfb {} ended at once ({status})", display.name);
        }
        assert!(started.elapsed() < Duration::from_secs(30), "Xvfb {} did not start", display.name);
        std::thread::sleep(Duration::from_millis(50));
    }
    display
}

fn carus() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_carus"));
    command.env("NODEVICE_SELECT", "1").env_remove("WAYLAND_DISPLAY");
    command
}

#[test]
fn the_viewer_opens_its_window_and_draws_a_run() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let coarse = [
        "numerics.end_time_s=0.2",
        "numerics.rigid_dt_s=0.001",
        "numerics.head_subdivisions=3",
        "contact.sample_spacing_mm=8",
        "floor.mesh.elements_around=16",
        "floor.mesh.elements_across=3",
    ];
    let mut simulate = carus();
    simulate.args(["run", "normal", "--quiet", "--json", "--out"]).arg(&run);
    for setting in coarse {
        simulate.args(["--set", setting]);
    }
    assert!(simulate.stdout(Stdio::null()).status().unwrap().success());

    let display = virtual_display();
    let shot = dir.path().join("window.png");
    let mut viewer = carus().arg("view").arg(&run).args(["--landmarks", "--forces"]).arg("--screenshot").arg(&shot).env("DISPLAY", &display.name).spawn().unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(status) = viewer.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > Duration::from_secs(180) {
            let _ = viewer.kill();
            panic!("the viewer's window did not save its screenshot and close within 180 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "carus view ended with {status}");

    let picture = carus_render::Image::decode_png(&std::fs::read(&shot).unwrap()).unwrap();
    let (w, h) = (picture.width() as usize, picture.height() as usize);
    let pixel = |x: usize, y: usize| &picture.pixels()[4 * (y * w + x)..4 * (y * w + x) + 4];
    // The 3D panel, right of the controls: its top right corner is background.
    let background = pixel(w - 2, 2).to_vec();
    let drawn = (0..h).flat_map(|y| (w / 3..w).map(move |x| (x, y))).filter(|&(x, y)| pixel(x, y) != &background[..]).count();
    assert!(drawn > w * h / 20, "only {drawn} pixels of the 3D panel drawn");
    // The controls' text in the left panel.
    let left_background = pixel(2, h - 2).to_vec();
    let text = (0..h / 3).flat_map(|y| (0..w / 5).map(move |x| (x, y))).filter(|&(x, y)| pixel(x, y) != &left_background[..]).count();
    assert!(text > 200, "the controls show only {text} pixels");
}
