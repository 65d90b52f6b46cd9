//! The interactive viewer (`carus view RUN`): a run replayed in a window,
//! the pelvis see-through, the fetus where the pose history has it and the
//! floor at its recorded state nearest in time, with a time slider, play
//! and pause, an orbiting camera, the standard views, and the station,
//! theta, phi and the movements under way read out beside it.
//!
//! The replay ([`Replay`]) and the camera ([`Orbit`]) are plain data, so
//! what a frame shows is tested without a window, and [`Replay::picture`]
//! draws any frame offscreen (`carus view RUN --at T --picture FILE`). The
//! window ([`open`]) only adds egui's controls; it draws the same meshes
//! with the renderer's painter inside egui's render pass.
//!
//! Two layers can be laid over a frame ([`Layers`]): the pelvis's
//! landmarks, obstetric planes and axis ([`Replay::with_markers`]), and
//! the forces on the fetus as arrows ([`Replay::with_forces`], module
//! [`forces`]).

pub mod forces;
mod window;

use carus_analysis::measures::wrap_deg;
use carus_analysis::{occiput_position, DetectorReport, PoseHistory, Series};
use carus_render::{Bounds, Camera, Image, Projection, RenderError, RenderMesh, Renderer, Scene, View};
use forces::Forces;
use carus_report::pictures::{fitting_bounds, meshes_at_sample, nearest_frame, see_through_under_forces, stretch_range};
use carus_report::ReportScene;
use glam::Vec3;

pub use window::{open, Follow};

/// Why a run cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("the pose history has no samples: there is nothing to replay")]
    NoSamples,
    #[error("the scene has no vertices to fit the camera to")]
    NoBounds,
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("the forces cannot be drawn: {0}")]
    Contact(#[from] carus_contact::ContactError),
    #[error("the window could not be opened: {0}\n  hint: the viewer needs a display (X11) and a Vulkan driver (a GPU's, or Mesa's: `apt-get install mesa-vulkan-drivers libvulkan1`); without a display, `carus view RUN --at T --picture FILE` draws a frame to a PNG")]
    Window(String),
    #[error("the screenshot {path} was not saved: {problem}")]
    Screenshot { path: std::path::PathBuf, problem: String },
    #[error("the detector's record is not this pose history's ({problem}): the run's record is damaged; run the scenario again, or `carus detect` its pose_history.csv")]
    SeriesMismatch { problem: String },
}

/// Theta as the history keeps it, continuous (a turn on past OP goes on
/// past 180 deg), with its value within -180 to 180 when that differs and
/// the occiput position it names.
fn theta_words(theta_deg: f64) -> String {
    match wrap_deg(theta_deg) {
        w if theta_deg.abs() <= 180.0 => format!("theta {theta_deg:.1} deg, occiput {}", occiput_position(w)),
        w => format!("theta {theta_deg:.1} deg (= {w:+.1}), occiput {}", occiput_position(w)),
    }
}

/// A detector's series read beside a history must be that history's, sample
/// for sample: the readout indexes both alike.
fn check_series(series: &Series, history: &PoseHistory) -> Result<(), ViewError> {
    let (n, m) = (series.len(), history.samples.len());
    if n != m {
        return Err(ViewError::SeriesMismatch { problem: format!("{n} samples against the history's {m}") });
    }
    match series.time_s.iter().zip(&history.samples).position(|(t, s)| *t != s.time_s) {
        Some(k) => Err(ViewError::SeriesMismatch {
            problem: format!("its sample {k} is at {} s, the history's at {} s", series.time_s[k], history.samples[k].time_s),
        }),
        None => Ok(()),
    }
}

/// A recorded run, ready to be shown at any of its samples.
pub struct Replay {
    pub title: String,
    scene: ReportScene,
    history: PoseHistory,
    series: Series,
    /// The seven movements: key, start and end (observed ones only).
    movements: Vec<(&'static str, f64, f64)>,
    stretch_range: Option<[f64; 2]>,
    /// What the camera is fitted to: the canal, and the head from the start
    /// to its birth.
    bounds: Bounds,
    /// The pelvis's landmarks, planes and axis (pelvis frame), if given.
    markers: Vec<RenderMesh>,
    /// The head's landmarks in its body frame, moved with it.
    head_markers: HeadMarkers,
    /// The run's loads, if given.
    forces: Option<Forces>,
}

/// The head's landmarks, drawn where the head is.
#[derive(Debug, Clone, Default)]
struct HeadMarkers {
    points: Vec<(String, glam::DVec3)>,
    radius_m: f32,
    rgb: [f32; 3],
}

/// What one sample of a replay shows ([`Replay::state`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SampleState {
    pub time_s: f64,
    pub station_mm: f64,
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Both parietal eminences below the inlet plane (engagement's test,
    /// CARDINAL_MOVEMENTS.md).
    pub head_engaged: bool,
    pub head_delivered: bool,
    /// The observed movements whose span holds the sample, by canonical key.
    pub under_way: Vec<&'static str>,
}

/// What is laid over a frame besides the anatomy.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Layers {
    /// The pelvis's landmarks, obstetric planes and axis, and the head's
    /// landmarks.
    pub markers: bool,
    /// The forces on the fetus as arrows.
    pub forces: bool,
}

impl Replay {
    /// A replay of `history` with the surfaces of `scene` (the report's),
    /// and the detector's movements when there is a report.
    pub fn new(
        title: impl Into<String>,
        scene: ReportScene,
        history: PoseHistory,
        detector: Option<&DetectorReport>,
    ) -> Result<Replay, ViewError> {
        if history.samples.is_empty() {
            return Err(ViewError::NoSamples);
        }
        if let Some(d) = detector {
            check_series(&d.series, &history)?;
        }
        let series = detector.map_or_else(|| Series::from_history(&history), |d| d.series.clone());
        let movements = detector.map_or_else(Vec::new, |d| {
            d.movements
                .by_key()
                .iter()
                .filter(|(_, m)| m.observed)
                .filter_map(|(key, m)| Some((*key, m.start_s?, m.end_s?)))
                .collect()
        });
        let stretch_range = scene.floor.as_ref().and_then(|f| stretch_range(f, None));
        // The head's path to its birth stays in view: the canal and the head
        // at the start, and the head as it is born (or at its deepest, if it
        // never is); after birth it may swing out of the canal's picture.
        let last = history.samples.len() - 1;
        let born_or_deepest = series.head_delivered.iter().position(|&born| born).unwrap_or_else(|| {
            (0..series.station_mm.len())
                .filter(|&k| series.station_mm[k].is_finite())
                .max_by(|&a, &b| series.station_mm[a].total_cmp(&series.station_mm[b]))
                .unwrap_or(0)
        });
        let framed: Vec<RenderMesh> = [0, born_or_deepest.min(last)]
            .into_iter()
            .flat_map(|k| meshes_at_sample(&scene, &history, k, stretch_range).0)
            .collect();
        let bounds = fitting_bounds(&framed).ok_or(ViewError::NoBounds)?;
        Ok(Replay {
            title: title.into(),
            scene,
            history,
            series,
            movements,
            stretch_range,
            bounds,
            markers: Vec::new(),
            head_markers: HeadMarkers::default(),
            forces: None,
        })
    }

    /// The replay with the pelvis's landmarks, planes and axis to lay over
    /// it (meshes in the pelvis frame).
    pub fn with_markers(mut self, markers: Vec<RenderMesh>) -> Replay {
        self.markers = markers;
        self
    }

    /// The replay with the run's loads (`run.json`'s `loads`), drawn as
    /// arrows: `pivot_in_head_m` is the point their moments are taken
    /// about, and `expulsion_at_pivot` says where the expulsion acts.
    pub fn with_forces(
        mut self,
        loads: Vec<carus_labour::loads::LoadSample>,
        pivot_in_head_m: glam::DVec3,
        expulsion_at_pivot: bool,
    ) -> Result<Replay, ViewError> {
        self.forces = Some(Forces::new(loads, pivot_in_head_m, expulsion_at_pivot, &self.scene)?);
        Ok(self)
    }

    /// The replay with the head's landmarks (name, point in the head's
    /// body frame) drawn with it as spheres of `radius_m` in `rgb`, with the
    /// pelvis's markers.
    pub fn with_head_markers(mut self, points: Vec<(String, glam::DVec3)>, radius_m: f32, rgb: [f32; 3]) -> Replay {
        self.head_markers = HeadMarkers { points, radius_m, rgb };
        self
    }

    /// The layers this replay can lay over its frames.
    pub fn layers_available(&self) -> Layers {
        Layers {
            markers: !self.markers.is_empty() || !self.head_markers.points.is_empty(),
            forces: self.forces.is_some(),
        }
    }

    /// Time of the last sample, s.
    pub fn duration_s(&self) -> f64 {
        self.history.samples.last().map_or(0.0, |s| s.time_s)
    }

    /// The sample shown at time `t`: the last one at or before it (the
    /// first before the run's start).
    pub fn sample_at(&self, t: f64) -> usize {
        self.history.samples.partition_point(|s| s.time_s <= t).saturating_sub(1)
    }

    /// The meshes of sample `k` (fetus, floor, pelvis), as the report draws
    /// them, then the layers asked for that the replay has: the markers,
    /// then one arrow per force drawn.
    pub fn meshes(&self, k: usize, layers: Layers) -> Vec<RenderMesh> {
        let mut meshes = meshes_at_sample(&self.scene, &self.history, k, self.stretch_range).0;
        if layers.markers {
            meshes.extend(self.markers.iter().cloned());
            let head = &self.history.samples[k].head;
            let HeadMarkers { points, radius_m, rgb } = &self.head_markers;
            meshes.extend(points.iter().map(|(name, p)| RenderMesh::sphere(name.clone(), head.point(*p).as_vec3().to_array(), *radius_m, *rgb)));
        }
        if let Some(forces) = self.forces.as_ref().filter(|_| layers.forces) {
            see_through_under_forces(&mut meshes);
            meshes.extend(forces.arrows(&self.history, k).iter().map(|a| a.mesh()));
        }
        meshes
    }

    /// The forces of sample `k` in words, largest first (none without loads).
    pub fn force_readout(&self, k: usize) -> Vec<String> {
        self.forces.as_ref().map_or_else(Vec::new, |f| f.readout(&self.history, k))
    }

    /// The arrows of sample `k` (none without loads).
    pub fn arrows(&self, k: usize) -> Vec<forces::Arrow> {
        self.forces.as_ref().map_or_else(Vec::new, |f| f.arrows(&self.history, k))
    }

    /// What sample `k` shows, as numbers: its time, the head's station,
    /// theta and phi (CARDINAL_MOVEMENTS.md), whether the head is born,
    /// and the movements under way.
    pub fn state(&self, k: usize) -> SampleState {
        let s = &self.series;
        let time_s = s.time_s[k];
        SampleState {
            time_s,
            station_mm: s.station_mm[k],
            theta_deg: s.theta_deg[k],
            phi_deg: s.phi_deg[k],
            head_engaged: s.engaged(k),
            head_delivered: s.head_delivered[k],
            under_way: self
                .movements
                .iter()
                .filter(|(_, start, end)| (*start..=*end).contains(&time_s))
                .map(|(key, _, _)| *key)
                .collect(),
        }
    }

    /// What sample `k` shows, in words: [`Replay::state`] and the floor's
    /// state drawn.
    pub fn readout(&self, k: usize) -> Vec<String> {
        let s = self.state(k);
        vec![
            format!("t = {:.2} s", s.time_s),
            format!("station {:+.1} mm", s.station_mm),
            theta_words(s.theta_deg),
            format!("phi {:.1} deg (flexion positive)", s.phi_deg),
            match (s.head_delivered, s.head_engaged) {
                (true, _) => "head delivered".into(),
                (false, true) => "head engaged, in the canal".into(),
                (false, false) => "head not engaged (its widest part above the inlet)".into(),
            },
            self.floor_shown(s.time_s),
            match s.under_way.is_empty() {
                true => "no movement under way".into(),
                false => format!("under way: {}", s.under_way.join(", ").replace('_', " ")),
            },
        ]
    }

    /// Which state of the floor a frame at time `t` shows: the recorded
    /// one nearest in time (docs/VIEWER.md).
    fn floor_shown(&self, t: f64) -> String {
        let Some(floor) = &self.scene.floor else {
            return "no pelvic floor".into();
        };
        nearest_frame(floor, t)
            .map(|f| f.time_s)
            .map_or("floor at rest (no state recorded)".into(), |at| match self.stretch_range {
                Some([low, high]) => format!("floor as at t = {at:.2} s; colour: stretch {low:.2} (dark) to {high:.2} (bright)"),
                None => format!("floor as at t = {at:.2} s"),
            })
    }

    /// The floor's colour scale from its frames before `t_s` only, as the
    /// report reads it ([`stretch_range`]): the run's floor had an element turned
    /// inside out then (docs/LABOUR.md), and the stretches after it, not to
    /// be trusted, would stretch the scale until the floor before looked at
    /// rest. All frames set it when none comes that early.
    pub fn with_stretch_scale_before(mut self, t_s: f64) -> Replay {
        let Some(floor) = &self.scene.floor else {
            return self;
        };
        self.stretch_range = stretch_range(floor, Some(t_s));
        self
    }

    /// The camera of `orbit`, fitted to the canal: zoom narrows the field
    /// kept in view, or in perspective the field of view from the same eye.
    pub fn camera(&self, orbit: &Orbit) -> Camera {
        let mut camera = Camera::fitted(orbit.eye_direction(), Vec3::Z, &self.bounds, orbit.projection);
        // Half the canal's longest side, not its box as seen from here,
        // so the scale holds while the camera circles.
        let longest = (0..3).map(|i| self.bounds.max[i] - self.bounds.min[i]).fold(0.0, f32::max);
        camera.half_extent = [0.5 * longest * ORBIT_MARGIN / orbit.zoom; 2];
        if let Projection::Perspective { fov_y } = orbit.projection {
            camera.projection = Projection::Perspective { fov_y: 2.0 * ((0.5 * fov_y).tan() / orbit.zoom).atan() };
        }
        camera
    }

    /// A standard view of the canal, as the report's pictures and `carus
    /// render` draw it.
    pub fn standard_camera(&self, view: View) -> Camera {
        Camera::standard(view, &self.bounds)
    }

    /// Draws the frame at time `t` with `layers` seen by `camera`
    /// offscreen (a GPU or Mesa's lavapipe).
    pub fn picture(&self, t: f64, camera: &Camera, layers: Layers, width: u32, height: u32) -> Result<Image, ViewError> {
        let mut renderer = Renderer::new_headless()?;
        let scene = Scene::new(self.meshes(self.sample_at(t), layers));
        Ok(renderer.render(&scene, camera, width, height)?)
    }
}

/// The viewer's camera: it circles the canal, its azimuth about the
/// pelvis frame's z (cranial) and its elevation above the transverse
/// plane, and zooms by shrinking the field kept in view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// Azimuth, radians: 0 looks from the mother's right (the lateral view).
    pub azimuth: f32,
    /// Elevation, radians, kept short of the poles so that up stays up.
    pub elevation: f32,
    /// 1 shows the whole canal; 2 half of it.
    pub zoom: f32,
    pub projection: Projection,
}

/// Room around the canal in the window's view.
const ORBIT_MARGIN: f32 = 1.1;
/// How close to straight up or down the camera may look, radians.
const MAX_ELEVATION: f32 = 1.45;
/// Zoom range.
const ZOOM: (f32, f32) = (0.5, 8.0);

impl Orbit {
    /// The orbit that looks as a standard view does. From straight below
    /// or above, where the view's up is anterior, the camera leans off the
    /// pole (towards the pubis from below, the sacrum from above) so that
    /// the pubis stays at the top of the picture as in the standard view.
    pub fn from_view(view: View) -> Orbit {
        let (eye, up) = view.eye_direction_and_up();
        let lean = if eye.z < 0.0 { up } else { -up };
        let azimuth = match eye.x.hypot(eye.y) > 1e-6 {
            true => eye.y.atan2(eye.x),
            false => lean.y.atan2(lean.x),
        };
        Orbit {
            azimuth,
            elevation: eye.z.clamp(-1.0, 1.0).asin().clamp(-MAX_ELEVATION, MAX_ELEVATION),
            zoom: 1.0,
            projection: Projection::Orthographic,
        }
    }

    /// Unit vector from the canal towards the eye.
    pub fn eye_direction(&self) -> Vec3 {
        let (sa, ca) = self.azimuth.sin_cos();
        let (se, ce) = self.elevation.sin_cos();
        Vec3::new(ce * ca, ce * sa, se)
    }

    /// Turns the camera by a drag of `dx`, `dy` radians (right, down).
    pub fn drag(&mut self, dx: f32, dy: f32) {
        self.azimuth = (self.azimuth - dx).rem_euclid(std::f32::consts::TAU);
        self.elevation = (self.elevation + dy).clamp(-MAX_ELEVATION, MAX_ELEVATION);
    }

    /// Zooms by `factor` (above 1: closer), within the zoom range.
    pub fn zoom_by(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.zoom = (self.zoom * factor).clamp(ZOOM.0, ZOOM.1);
        }
    }
}

#[cfg(test)]
mod tests;
