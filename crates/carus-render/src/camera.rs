//! Cameras in the pelvis frame of CONVENTIONS.md (x to the mother's
//! right, y anterior, z cranial), with the standard anatomical views.

use glam::camera::rh::{proj::directx, view::look_at_mat4};
use glam::{Mat4, Vec3, Vec4Swizzles};

use crate::mesh::Bounds;

/// Standard anatomical viewing directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum View {
    /// From the front (+y) towards -y, cranial up: the mother's right is on
    /// the picture's left, as when facing a patient.
    Anterior,
    /// From the mother's right (+x) towards -x, cranial up: anterior is on
    /// the picture's right.
    Lateral,
    /// Outlet view, from below (-z) looking cranially, anterior (pubis) up:
    /// the mother's right is on the picture's left, as in lithotomy.
    Inferior,
    /// Inlet view, from above (+z) looking caudally, anterior (pubis) up:
    /// the mother's right is on the picture's right.
    Superior,
    /// Three-quarter view from anterior, right and above, cranial up.
    Oblique,
}

impl View {
    /// Every standard view.
    pub const ALL: [View; 5] = [
        View::Anterior,
        View::Lateral,
        View::Inferior,
        View::Superior,
        View::Oblique,
    ];

    /// The three views of a standard anatomy figure.
    pub const THREE: [View; 3] = [View::Anterior, View::Lateral, View::Inferior];

    /// Lower-case name, as used in file names ("anterior").
    pub fn name(self) -> &'static str {
        match self {
            View::Anterior => "anterior",
            View::Lateral => "lateral",
            View::Inferior => "inferior",
            View::Superior => "superior",
            View::Oblique => "oblique",
        }
    }

    /// Where the eye is and which way the mother's body lies in the
    /// picture (pelvis frame, CONVENTIONS.md: x her right, y anterior, z
    /// cranial): the view's name alone does not tell inferior from
    /// superior, which are mirror images. At most 48 characters, the
    /// width of a 384 px tile.
    pub fn orientation(self) -> &'static str {
        match self {
            View::Anterior => "from front: cranial up, her left to the right",
            View::Lateral => "from her right: cranial up, front to the right",
            View::Inferior => "from below: front up, her left to the right",
            View::Superior => "from above: front up, her right to the right",
            View::Oblique => "from her front right, above: cranial up",
        }
    }

    /// Unit vector from the looked-at point towards the eye, and the
    /// direction that appears upwards in the picture, both in the pelvis frame.
    pub fn eye_direction_and_up(self) -> (Vec3, Vec3) {
        match self {
            View::Anterior => (Vec3::Y, Vec3::Z),
            View::Lateral => (Vec3::X, Vec3::Z),
            View::Inferior => (-Vec3::Z, Vec3::Y),
            View::Superior => (Vec3::Z, Vec3::Y),
            View::Oblique => (Vec3::new(1.0, 1.2, 0.8).normalize(), Vec3::Z),
        }
    }
}

/// How the scene is projected onto the picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Parallel projection: sizes in the picture are true to scale, as in
    /// an anatomy atlas.
    Orthographic,
    /// Central projection with a vertical field of view in radians.
    Perspective {
        /// Vertical field of view (rad), between 0 and pi.
        fov_y: f32,
    },
}

/// Empty space left around the fitted scene, as a fraction of its extent.
const FIT_MARGIN: f32 = 0.06;

/// A camera looking at a target from a direction, fitted to some bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Point looked at (centre of the picture).
    pub target: Vec3,
    /// Unit vector from the target towards the eye.
    pub eye_direction: Vec3,
    /// Direction that appears upwards in the picture (need not be orthogonal
    /// to `eye_direction`, only not parallel to it).
    pub up: Vec3,
    /// Distance from the target to the eye.
    pub distance: f32,
    /// Half width and half height (scene units, in the plane through the
    /// target) that must stay visible whatever the picture's aspect ratio.
    pub half_extent: [f32; 2],
    /// Near and far clipping distances from the eye.
    pub depth_range: [f32; 2],
    /// Projection.
    pub projection: Projection,
}

impl Camera {
    /// An orthographic camera for a standard view, fitted to `bounds` with a
    /// small margin.
    pub fn standard(view: View, bounds: &Bounds) -> Self {
        let (eye_direction, up) = view.eye_direction_and_up();
        Self::fitted(eye_direction, up, bounds, Projection::Orthographic)
    }

    /// A camera looking along `-eye_direction` with `up` upwards, fitted to `bounds`.
    pub fn fitted(eye_direction: Vec3, up: Vec3, bounds: &Bounds, projection: Projection) -> Self {
        let eye_direction = eye_direction.try_normalize().unwrap_or(Vec3::Y);
        let target = bounds.centre();
        // A point (or empty) bounds still needs a finite, non-zero view volume.
        let radius = bounds.radius().max(1e-6 * (1.0 + target.length()));
        let mut camera = Self {
            target,
            eye_direction,
            up,
            distance: 2.0 * radius,
            half_extent: [radius, radius],
            depth_range: [0.5 * radius, 3.5 * radius],
            projection,
        };
        let (right, up_in_picture, _) = camera.basis();
        let (mut half_w, mut half_h) = (0.0_f32, 0.0_f32);
        for corner in bounds.corners() {
            let d = corner - target;
            half_w = half_w.max(d.dot(right).abs());
            half_h = half_h.max(d.dot(up_in_picture).abs());
        }
        let grow = 1.0 + FIT_MARGIN;
        camera.half_extent = [
            (half_w * grow).max(radius * 1e-3),
            (half_h * grow).max(radius * 1e-3),
        ];
        if let Projection::Perspective { fov_y } = projection {
            // Far enough that the bounding sphere fits the narrower field.
            let half_fov = (0.5 * fov_y).clamp(1e-3, 1.5);
            camera.distance = radius * grow / half_fov.sin();
            camera.depth_range = [
                (camera.distance - 1.5 * radius).max(camera.distance * 1e-3),
                camera.distance + 1.5 * radius,
            ];
        }
        camera
    }

    /// The same camera with another projection, refitted.
    pub fn with_projection(self, projection: Projection, bounds: &Bounds) -> Self {
        Self::fitted(self.eye_direction, self.up, bounds, projection)
    }

    /// Eye position.
    pub fn eye(&self) -> Vec3 {
        self.target + self.eye_direction * self.distance
    }

    /// Picture right, picture up and towards-the-eye unit vectors in the scene frame.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let back = self.eye_direction;
        let right = self
            .up
            .cross(back)
            .try_normalize()
            .unwrap_or_else(|| back.any_orthonormal_vector());
        (right, back.cross(right), back)
    }

    /// Scene-to-view transform (right-handed, looking down -z).
    pub fn view_matrix(&self) -> Mat4 {
        let (_, up, _) = self.basis();
        look_at_mat4(self.eye(), self.target, up)
    }

    /// View-to-clip transform for a picture of the given aspect (width / height),
    /// depth 0..1 and y up as wgpu expects (the
    /// "directx" convention of glam).
    pub fn projection_matrix(&self, aspect: f32) -> Mat4 {
        let [near, far] = self.depth_range;
        match self.projection {
            Projection::Orthographic => {
                let [w, h] = self.half_extent;
                let half_h = h.max(w / aspect);
                let half_w = half_h * aspect;
                directx::orthographic(-half_w, half_w, -half_h, half_h, near, far)
            }
            Projection::Perspective { fov_y } => {
                // Keep the horizontal field at least the nominal one in tall pictures.
                let half_tan = (0.5 * fov_y).tan();
                let fov = 2.0 * (half_tan / aspect.min(1.0)).atan();
                directx::perspective(fov, aspect, near, far)
            }
        }
    }

    /// Scene-to-clip transform.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection_matrix(aspect) * self.view_matrix()
    }

    /// Pixel coordinates (x right, y down, pixel centres at +0.5) of a scene
    /// point in a picture of `width` x `height`.
    pub fn project(&self, point: Vec3, width: u32, height: u32) -> [f32; 2] {
        let clip = self.view_projection(width as f32 / height as f32) * point.extend(1.0);
        let ndc = clip.xy() / clip.w;
        [
            (ndc.x + 1.0) * 0.5 * width as f32,
            (1.0 - ndc.y) * 0.5 * height as f32,
        ]
    }

    /// Distance of a point in front of the eye along the viewing direction
    /// (larger is farther): the key for drawing transparent meshes back to front.
    pub fn depth_of(&self, point: Vec3) -> f32 {
        (self.eye() - point).dot(self.eye_direction)
    }

    /// True for orthographic projection.
    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each view's orientation text says what its camera shows: the
    /// picture's up and right directions, named in the pelvis frame.
    #[test]
    fn each_view_says_which_way_the_body_lies() {
        // The axis `v` lies along (within `tolerance` of its cosine), named.
        let word = |v: Vec3, tolerance: f32| -> Option<&'static str> {
            let axes = [(Vec3::X, "her right"), (Vec3::Y, "front"), (Vec3::Z, "cranial")];
            let opposite = ["her left", "posterior", "caudal"];
            axes.iter().zip(opposite).find_map(|((axis, plus), minus)| match v.dot(*axis) {
                d if d > tolerance => Some(*plus),
                d if d < -tolerance => Some(minus),
                _ => None,
            })
        };
        for view in View::ALL {
            let (eye, up) = view.eye_direction_and_up();
            let camera = Camera::fitted(eye, up, &unit_box(), Projection::Orthographic);
            let (right, up, _) = camera.basis();
            let text = view.orientation();
            assert!(text.len() <= 48, "{view:?}: {text}");
            // The oblique view's up leans: named by the axis it is nearest.
            assert!(text.contains(&format!("{} up", word(up, 0.7).unwrap())), "{view:?}: {text}");
            if let Some(right) = word(right, 0.99) {
                assert!(text.contains(&format!("{right} to the right")), "{view:?}: {text}");
            }
        }
    }

    fn unit_box() -> Bounds {
        Bounds {
            min: [-0.5, -0.5, -0.5],
            max: [0.5, 0.5, 0.5],
        }
    }

    #[test]
    fn anterior_view_shows_mothers_right_on_the_left() {
        let cam = Camera::standard(View::Anterior, &unit_box());
        let right = cam.project(Vec3::new(0.4, 0.0, 0.0), 100, 100);
        let cranial = cam.project(Vec3::new(0.0, 0.0, 0.4), 100, 100);
        assert!(right[0] < 50.0, "mother's right at x = {}", right[0]);
        assert!(cranial[1] < 50.0, "cranial at y = {}", cranial[1]);
    }

    #[test]
    fn lateral_view_shows_anterior_on_the_right() {
        let cam = Camera::standard(View::Lateral, &unit_box());
        assert!(cam.project(Vec3::new(0.0, 0.4, 0.0), 100, 100)[0] > 50.0);
    }

    #[test]
    fn inferior_and_superior_views_put_the_pubis_up() {
        for view in [View::Inferior, View::Superior] {
            let cam = Camera::standard(view, &unit_box());
            assert!(
                cam.project(Vec3::new(0.0, 0.4, 0.0), 100, 100)[1] < 50.0,
                "{view:?}"
            );
        }
        let below = Camera::standard(View::Inferior, &unit_box());
        assert!(below.project(Vec3::new(0.4, 0.0, 0.0), 100, 100)[0] < 50.0);
        let above = Camera::standard(View::Superior, &unit_box());
        assert!(above.project(Vec3::new(0.4, 0.0, 0.0), 100, 100)[0] > 50.0);
    }

    #[test]
    fn orthographic_fit_keeps_the_box_inside_with_its_margin() {
        for view in View::ALL {
            let cam = Camera::standard(view, &unit_box());
            for (w, h) in [(100, 100), (200, 100), (100, 300)] {
                for corner in unit_box().corners() {
                    let [x, y] = cam.project(corner, w, h);
                    assert!(
                        (0.0..=w as f32).contains(&x) && (0.0..=h as f32).contains(&y),
                        "{view:?}"
                    );
                }
            }
        }
        // Anterior view of a unit cube: the cube spans 1 / 1.06 of the picture.
        let cam = Camera::standard(View::Anterior, &unit_box());
        let left = cam.project(Vec3::new(0.5, 0.0, 0.0), 106, 106)[0];
        let right = cam.project(Vec3::new(-0.5, 0.0, 0.0), 106, 106)[0];
        assert!((right - left - 100.0).abs() < 1e-3, "{}", right - left);
    }

    #[test]
    fn perspective_fit_keeps_the_box_inside() {
        let bounds = unit_box();
        let cam = Camera::standard(View::Oblique, &bounds)
            .with_projection(Projection::Perspective { fov_y: 0.6 }, &bounds);
        for (w, h) in [(100, 100), (50, 100)] {
            for corner in bounds.corners() {
                let [x, y] = cam.project(corner, w, h);
                assert!((0.0..=w as f32).contains(&x) && (0.0..=h as f32).contains(&y));
                let depth = cam.depth_of(corner);
                assert!(depth > cam.depth_range[0] && depth < cam.depth_range[1]);
            }
        }
    }
}
