//! The window: egui's controls beside a 3D panel that the renderer's
//! painter draws into egui's own render pass (an `egui_wgpu` paint
//! callback), so the scene and the controls share one device and one pass.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use carus_render::{Camera, GpuMesh, Lights, MeshPainter, Projection, RenderMesh, TargetFormat, View};
use carus_report::pictures::PELVIS;
use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};

use crate::{Layers, Orbit, Replay, ViewError};

/// Depth buffer bits asked of eframe; the painter's pipelines are built for
/// the format eframe makes of them.
const DEPTH_BITS: u8 = 24;
/// Samples per pixel in the window, as in the report's pictures.
const SAMPLES: u32 = 4;
/// Radians the camera turns per point dragged.
const DRAG_RADIANS_PER_POINT: f32 = 0.01;
/// Width of the time slider, points.
const SLIDER_WIDTH: f32 = 200.0;
/// Playback speeds offered, simulated seconds per second.
const SPEEDS: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// Frames drawn before a screenshot is taken, so that the scene's meshes
/// are uploaded and the layout has settled.
const FRAMES_BEFORE_SCREENSHOT: u32 = 5;
/// How long the window waits for egui to hand back the screenshot.
const SCREENSHOT_DEADLINE: Duration = Duration::from_secs(30);
/// The longest step of playback, s of wall time: after a stall the replay
/// goes on where it was rather than jumping.
const MAX_PLAYBACK_STEP_S: f32 = 0.1;
/// How often the window asks a run still going for more, s of wall time.
const FOLLOW_EVERY: Duration = Duration::from_secs(1);

/// A run still going, as the window follows it: each call gives the run's
/// replay again if it has written more since the last call, and whether
/// it still goes on (false once it has written its record).
pub type Follow = Box<dyn FnMut() -> Option<(Replay, bool)>>;

/// Opens the viewer on `replay` at time `start_s` from `view` with
/// `layers` shown, and returns when its window is closed. With
/// `screenshot`, the window saves a PNG of itself once drawn and closes
/// (what the tests check, and a picture of the viewer for docs). With
/// `follow`, the window asks it for more every second and shows what it
/// gives, at the newest time while "follow the run" is ticked.
pub fn open(
    replay: Replay,
    start_s: f64,
    view: View,
    layers: Layers,
    screenshot: Option<PathBuf>,
    follow: Option<Follow>,
) -> Result<(), ViewError> {
    #[cfg(all(unix, not(target_os = "macos")))]
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err(ViewError::Window("no display: DISPLAY is not set".into()));
    }
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_inner_size([1200.0, 800.0]).with_title(replay.title.clone()),
        depth_buffer: DEPTH_BITS,
        multisampling: SAMPLES as u16,
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration { wgpu_setup: window_backends(), ..Default::default() },
        ..Default::default()
    };
    let title = replay.title.clone();
    let saved: Arc<Mutex<Option<Result<(), String>>>> = Arc::default();
    let shot = screenshot.clone().map(|path| Screenshot { path, frames_left: FRAMES_BEFORE_SCREENSHOT, asked: None, saved: saved.clone() });
    eframe::run_native(
        &title,
        options,
        Box::new(|cc| {
            let state = cc
                .wgpu_render_state
                .as_ref()
                .ok_or("eframe opened no wgpu device for the window")?;
            let target = TargetFormat {
                colour: state.target_format,
                depth: egui_wgpu::depth_format_from_bits(DEPTH_BITS, 0).ok_or("no depth format for the window")?,
                sample_count: SAMPLES,
            };
            let painter = MeshPainter::new(&state.device, &state.queue, target);
            state.renderer.write().callback_resources.insert(GpuScene { painter, meshes: Vec::new(), shown: None, pelvis_at: None });
            Ok(Box::new(Viewer {
                screenshot: shot,
                time_s: start_s,
                orbit: Orbit::from_view(view),
                layers,
                follow: follow.map(|f| Following { more: f, asked: Instant::now(), to_newest: true }),
                ..Viewer::new(replay)
            }))
        }),
    )
    .map_err(|e| ViewError::Window(without_source_path(&e.to_string())))?;
    let outcome = saved.lock().ok().and_then(|s| s.clone());
    match (screenshot, outcome) {
        (None, _) => Ok(()),
        (Some(_), Some(Ok(()))) => Ok(()),
        (Some(path), Some(Err(problem))) => Err(ViewError::Screenshot { path, problem }),
        (Some(path), None) => Err(ViewError::Screenshot { path, problem: "the window closed before it was taken".into() }),
    }
}

/// winit's errors say where in its source they arose ("os error at
/// /root/.cargo/.../mod.rs:788: Failed to open connection to X server"):
/// the user is told what failed, not where.
fn without_source_path(message: &str) -> String {
    match message.split_once(" at ").map(|(before, after)| (before, after.split_once(".rs:"))) {
        Some((before, Some((_, rest)))) => {
            let what = rest.split_once(": ").map_or(rest, |(_, what)| what);
            format!("{before}: {what}")
        }
        _ => message.to_string(),
    }
}

/// Vulkan, Metal or DX12 (wgpu's primary backends), or what `WGPU_BACKEND`
/// names. Without them eframe would fall back to OpenGL, whose window
/// stayed black on a virtual X display with Mesa (docs/VIEWER.md); left
/// out, the viewer says instead that it needs a Vulkan driver.
fn window_backends() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// A screenshot the window takes of itself, then closes.
struct Screenshot {
    path: PathBuf,
    frames_left: u32,
    /// When the picture was asked for.
    asked: Option<Instant>,
    /// Written by egui's screenshot callback: saved, or why not.
    saved: Arc<Mutex<Option<Result<(), String>>>>,
}

impl Screenshot {
    /// One frame's step: wait, ask for the picture, close once it is saved.
    fn step(&mut self, ctx: &egui::Context) {
        if self.frames_left > 0 {
            self.frames_left -= 1;
        } else if self.asked.is_none() {
            self.asked = Some(Instant::now());
            let (path, saved, repaint) = (self.path.clone(), self.saved.clone(), ctx.clone());
            ctx.request_screenshot(move |image| {
                let [w, h] = image.size;
                let rgba = image.pixels.iter().flat_map(|p| p.to_srgba_unmultiplied()).collect();
                let result = carus_render::Image::from_rgba(w as u32, h as u32, rgba)
                    .and_then(|picture| picture.save_png(&path))
                    .map_err(|e| e.to_string());
                if let Ok(mut slot) = saved.lock() {
                    *slot = Some(result);
                }
                repaint.request_repaint();
            });
        } else if let Ok(mut saved) = self.saved.lock() {
            if saved.is_none() && self.asked.is_some_and(|at| at.elapsed() > SCREENSHOT_DEADLINE) {
                *saved = Some(Err(format!("the window gave no picture within {} s", SCREENSHOT_DEADLINE.as_secs())));
            }
            if saved.is_some() {
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
        ctx.request_repaint();
    }
}

/// The painter and the meshes on the GPU, kept in egui's callback resources.
struct GpuScene {
    painter: MeshPainter,
    meshes: Vec<GpuMesh>,
    /// The sample and layers whose meshes are uploaded.
    shown: Option<Shown>,
    /// Where the pelvis is uploaded.
    pelvis_at: Option<usize>,
}

/// A replay (counted up each time a followed run gives a new one), one of
/// its samples and the layers laid over it.
type Shown = (u64, usize, Layers);

/// One frame of the 3D panel: what to draw and from where.
struct Frame {
    shown: Shown,
    meshes: Arc<Vec<RenderMesh>>,
    camera: Camera,
    aspect: f32,
}

impl egui_wgpu::CallbackTrait for Frame {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(scene) = resources.get_mut::<GpuScene>() else {
            return Vec::new();
        };
        if scene.shown != Some(self.shown) {
            // The pelvis stays as uploaded where it was uploaded. The rest is
            // rewritten in place where it kept its counts (the fetus, the
            // floor, an arrow redrawn), uploaded anew where not, and what is
            // no longer shown is dropped. A mesh that cannot be uploaded
            // ends the list there, and the next frame tries again.
            let mut complete = true;
            for (i, mesh) in self.meshes.iter().enumerate() {
                let kept = match scene.meshes.get_mut(i) {
                    Some(_) if mesh.name == PELVIS && scene.pelvis_at == Some(i) => true,
                    Some(gpu) => {
                        scene.painter.update(queue, gpu, mesh, i).is_ok()
                            || scene.painter.upload(device, mesh, i).map(|fresh| *gpu = fresh).is_ok()
                    }
                    None => scene.painter.upload(device, mesh, i).map(|gpu| scene.meshes.push(gpu)).is_ok(),
                };
                if !kept {
                    scene.meshes.truncate(i);
                    complete = false;
                    break;
                }
                if mesh.name == PELVIS {
                    scene.pelvis_at = Some(i);
                } else if scene.pelvis_at == Some(i) {
                    scene.pelvis_at = None;
                }
            }
            scene.meshes.truncate(self.meshes.len());
            scene.pelvis_at = scene.pelvis_at.filter(|&i| i < scene.meshes.len());
            scene.shown = complete.then_some(self.shown);
        }
        scene.painter.prepare(queue, &self.camera, &Lights::default(), self.aspect);
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        if let Some(scene) = resources.get::<GpuScene>() {
            scene.painter.paint(pass, &scene.meshes, &self.camera);
        }
    }
}

/// The viewer's state between frames.
struct Viewer {
    replay: Replay,
    time_s: f64,
    playing: bool,
    speed: f32,
    orbit: Orbit,
    /// What is laid over the anatomy.
    layers: Layers,
    /// The meshes of the sample and layers shown, rebuilt when either changes.
    meshes: Option<(Shown, Arc<Vec<RenderMesh>>)>,
    screenshot: Option<Screenshot>,
    /// A run still going, followed.
    follow: Option<Following>,
    /// How many replays a followed run has given.
    generation: u64,
}

/// A run followed as it goes on.
struct Following {
    more: Follow,
    /// When it was last asked for more.
    asked: Instant,
    /// Keep the slider at the newest time.
    to_newest: bool,
}

impl Viewer {
    fn new(replay: Replay) -> Viewer {
        Viewer {
            replay,
            time_s: 0.0,
            playing: false,
            speed: 1.0,
            orbit: Orbit::from_view(View::Lateral),
            layers: Layers::default(),
            meshes: None,
            screenshot: None,
            follow: None,
            generation: 0,
        }
    }

    /// Asks a followed run for more, once a second, and shows it.
    fn follow(&mut self, ctx: &egui::Context) {
        let Some(follow) = &mut self.follow else {
            return;
        };
        if follow.asked.elapsed() >= FOLLOW_EVERY {
            follow.asked = Instant::now();
            if let Some((replay, goes_on)) = (follow.more)() {
                let at_newest = self.time_s >= self.replay.duration_s();
                self.replay = replay;
                self.generation += 1;
                self.meshes = None;
                let newest = self.replay.duration_s();
                self.time_s = if follow.to_newest || at_newest { newest } else { self.time_s.min(newest) };
                if !goes_on {
                    self.follow = None;
                    return;
                }
            }
        }
        ctx.request_repaint_after(FOLLOW_EVERY);
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        let end = self.replay.duration_s();
        ui.heading(&self.replay.title);
        ui.horizontal(|ui| {
            if ui.button(if self.playing { "Pause" } else { "Play" }).clicked() {
                if !self.playing && self.time_s >= end {
                    self.time_s = 0.0;
                }
                self.playing = !self.playing;
            }
            egui::ComboBox::from_label("speed")
                .selected_text(format!("{}x", self.speed))
                .show_ui(ui, |ui| {
                    for s in SPEEDS {
                        ui.selectable_value(&mut self.speed, s, format!("{s}x"));
                    }
                });
        });
        // Wider than egui's default, for a finer hold on a long run; fixed,
        // since a width taken from the panel would grow the panel.
        ui.spacing_mut().slider_width = SLIDER_WIDTH;
        ui.add(egui::Slider::new(&mut self.time_s, 0.0..=end).text("t (s)"));
        if let Some(follow) = &mut self.follow {
            ui.checkbox(&mut follow.to_newest, "follow the run: keep to its newest time");
        }
        ui.separator();
        let sample = self.replay.sample_at(self.time_s);
        for line in self.replay.readout(sample) {
            ui.label(line);
        }
        ui.separator();
        let available = self.replay.layers_available();
        ui.add_enabled(available.markers, egui::Checkbox::new(&mut self.layers.markers, "landmarks (pelvis and head), planes and axis"));
        ui.add_enabled(available.forces, egui::Checkbox::new(&mut self.layers.forces, "forces on the fetus"));
        if self.layers.forces {
            self.force_legend(ui, sample);
        }
        ui.separator();
        ui.label("View (drag to turn, scroll to zoom)");
        ui.horizontal_wrapped(|ui| {
            for view in [View::Lateral, View::Anterior, View::Inferior, View::Superior, View::Oblique] {
                if ui.button(view.name()).clicked() {
                    self.orbit = Orbit::from_view(view);
                }
            }
        });
        let mut perspective = matches!(self.orbit.projection, Projection::Perspective { .. });
        if ui.checkbox(&mut perspective, "perspective").changed() {
            self.orbit.projection = match perspective {
                true => Projection::Perspective { fov_y: 0.6 },
                false => Projection::Orthographic,
            };
        }
    }

    /// Each force drawn, in its arrow's colour, largest first, and the
    /// arrows' scale.
    fn force_legend(&self, ui: &mut egui::Ui, sample: usize) {
        let arrows = crate::forces::largest_first(self.replay.arrows(sample));
        for arrow in &arrows {
            ui.horizontal(|ui| {
                let (swatch, _) = ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
                let [r, g, b] = arrow.rgb.map(|c| (c * 255.0).round() as u8);
                ui.painter().rect_filled(swatch, 2.0, egui::Color32::from_rgb(r, g, b));
                ui.label(format!("{} {:.0} N", arrow.label, arrow.force_n.length()));
            });
        }
        if arrows.is_empty() {
            ui.label(format!("no force of {} N or more", crate::forces::SMALLEST_DRAWN_N));
        }
        ui.label(format!("arrows: 10 mm per {:.0} N", 0.01 / crate::forces::ARROW_M_PER_N));
    }

    fn scene(&mut self, ui: &mut egui::Ui) {
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), egui::Sense::drag());
        let drag = response.drag_delta();
        self.orbit.drag(drag.x * DRAG_RADIANS_PER_POINT, drag.y * DRAG_RADIANS_PER_POINT);
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            self.orbit.zoom_by((scroll * 0.002).exp());
        }
        let shown = (self.generation, self.replay.sample_at(self.time_s), self.layers);
        let meshes = match &self.meshes {
            Some((k, meshes)) if *k == shown => meshes.clone(),
            _ => {
                let meshes = Arc::new(self.replay.meshes(shown.1, shown.2));
                self.meshes = Some((shown, meshes.clone()));
                meshes
            }
        };
        let frame = Frame {
            shown,
            meshes,
            camera: self.replay.camera(&self.orbit),
            aspect: rect.width().max(1.0) / rect.height().max(1.0),
        };
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(rect, frame));
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.follow(ui.ctx());
        if self.playing {
            let dt = ui.input(|i| i.stable_dt.min(MAX_PLAYBACK_STEP_S)) as f64 * self.speed as f64;
            self.time_s = (self.time_s + dt).min(self.replay.duration_s());
            self.playing = self.time_s < self.replay.duration_s();
            ui.ctx().request_repaint();
        }
        egui::Panel::left("controls").default_size(300.0).show(ui, |ui| self.controls(ui));
        egui::CentralPanel::default().show(ui, |ui| self.scene(ui));
        if let Some(shot) = &mut self.screenshot {
            shot.step(ui.ctx());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::without_source_path;

    #[test]
    fn a_window_error_says_what_failed_not_where() {
        let winit = "winit EventLoopError: os error at /root/.cargo/registry/src/x/winit-0.30.13/src/platform_impl/linux/mod.rs:788: Failed to open connection to X server";
        assert_eq!(without_source_path(winit), "winit EventLoopError: os error: Failed to open connection to X server");
        let plain = "WGPU error: Failed to create surface for any enabled backend";
        assert_eq!(without_source_path(plain), plain);
    }
}
