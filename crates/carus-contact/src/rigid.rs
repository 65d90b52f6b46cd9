//! Rigid bodies (fetal head, trunk): constant mass properties apart from the
//! mutable state, both as structures of arrays, advanced by a symplectic
//! (semi-implicit) Euler step.
//!
//! Rotation is carried as world angular momentum L, so a torque-free body
//! keeps L exactly. The gyroscopic motion is integrated by splitting the
//! kinetic energy into its three principal parts, each an exact rotation
//! about one principal axis, composed symmetrically (McLachlan 1993,
//! "Explicit Lie-Poisson integration and the Euler equations", Phys. Rev.
//! Lett. 71; Dullweber, Leimkuhler and McLachlan 1997): stable at any step,
//! time-reversible, energy bounded without drift. Written here rather than
//! taken from rapier: see docs/CONTACT.md.

use glam::{DMat3, DQuat, DVec3};
use parry3d_f64::math::SymmetricEigen3;
use serde::{Deserialize, Serialize};

use crate::error::{check_non_negative, ContactError};

pub use carus_anatomy::pose::RigidPose;

/// A force through the centre of mass and a torque, world frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Wrench {
    pub force: DVec3,
    pub torque: DVec3,
}

impl Wrench {
    /// The wrench about the centre of mass `com` of a force applied at `point`.
    pub fn at_point(force: DVec3, point: DVec3, com: DVec3) -> Self {
        Wrench { force, torque: (point - com).cross(force) }
    }
}

impl std::ops::Add for Wrench {
    type Output = Wrench;
    fn add(self, o: Wrench) -> Wrench {
        Wrench { force: self.force + o.force, torque: self.torque + o.torque }
    }
}

impl std::ops::AddAssign for Wrench {
    fn add_assign(&mut self, o: Wrench) {
        *self = *self + o;
    }
}

/// Mass properties of one body, its body frame centred on its centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MassProperties {
    pub mass_kg: f64,
    /// Inertia tensor about the centre of mass in the body frame, kg m^2.
    pub inertia_kg_m2: DMat3,
    /// Holds the orientation fixed (infinite inertia), e.g. for a sliding
    /// block test or a body steered only in translation.
    pub rotation_locked: bool,
}

/// Constant data of all bodies (structure of arrays).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RigidBodyModel {
    pub mass_kg: Vec<f64>,
    inverse_mass: Vec<f64>,
    /// Principal axes as a rotation from the principal frame to the body frame.
    principal_axes: Vec<DQuat>,
    /// Inverse principal moments (zero when rotation is locked), 1/(kg m^2).
    inverse_principal_inertia: Vec<DVec3>,
}

/// Mutable state of all bodies (structure of arrays); serializable for checkpoints.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RigidBodyState {
    /// Centre of mass, world, m.
    pub position: Vec<DVec3>,
    /// Body to world.
    pub orientation: Vec<DQuat>,
    pub linear_velocity: Vec<DVec3>,
    /// Angular momentum about the centre of mass, world, kg m^2/s.
    pub angular_momentum: Vec<DVec3>,
}

impl RigidBodyModel {
    /// Adds a body and returns its index.
    pub fn add(&mut self, props: MassProperties) -> Result<usize, ContactError> {
        let mass = check_non_negative("mass_kg", props.mass_kg, false)?;
        let i = props.inertia_kg_m2;
        let largest = i.abs().to_cols_array().into_iter().fold(0.0, f64::max);
        let asymmetry = (i - i.transpose()).abs().to_cols_array().into_iter().fold(0.0, f64::max);
        if !i.is_finite() || asymmetry > 1e-12 * largest {
            return Err(ContactError::InvalidParameter {
                name: "inertia_kg_m2",
                value: asymmetry,
                hint: "must be a finite symmetric matrix",
            });
        }
        let eigen = SymmetricEigen3::new(i);
        let mut axes = eigen.eigenvectors;
        if axes.determinant() < 0.0 {
            axes.z_axis = -axes.z_axis;
        }
        let moments = eigen.eigenvalues;
        if let Some(&bad) = moments.to_array().iter().find(|&&m| m.is_nan() || m <= 0.0) {
            return Err(ContactError::InvalidParameter {
                name: "inertia_kg_m2",
                value: bad,
                hint: "principal moments must be positive (a physical inertia tensor)",
            });
        }
        self.mass_kg.push(mass);
        self.inverse_mass.push(1.0 / mass);
        self.principal_axes.push(DQuat::from_mat3(&axes).normalize());
        self.inverse_principal_inertia.push(if props.rotation_locked { DVec3::ZERO } else { moments.recip() });
        Ok(self.mass_kg.len() - 1)
    }

    pub fn len(&self) -> usize {
        self.mass_kg.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass_kg.is_empty()
    }

    /// World inverse inertia of body `b` at orientation `q`.
    pub fn inverse_inertia_world(&self, b: usize, q: DQuat) -> DMat3 {
        let r = DMat3::from_quat(q * self.principal_axes[b]);
        r * DMat3::from_diagonal(self.inverse_principal_inertia[b]) * r.transpose()
    }

    /// Effective mass of body `b` for a push along unit `direction` at a
    /// point `lever` from its centre: 1 / (1/m + (r x n) . I^-1 (r x n)).
    /// The mass to use in [`crate::ContactLaw::critical_time_step`].
    pub fn effective_mass(&self, b: usize, q: DQuat, lever: DVec3, direction: DVec3) -> f64 {
        let rn = lever.cross(direction);
        1.0 / (self.inverse_mass[b] + rn.dot(self.inverse_inertia_world(b, q) * rn))
    }

    /// Smallest effective mass of body `b` over contacts within `radius_m`
    /// of its centre: 1 / (1/m + R^2 / I_min). A safe mass for the step limit.
    pub fn smallest_effective_mass(&self, b: usize, radius_m: f64) -> f64 {
        let largest_inverse = self.inverse_principal_inertia[b].max_element();
        1.0 / (self.inverse_mass[b] + radius_m * radius_m * largest_inverse)
    }
}

impl RigidBodyState {
    /// The first body whose pose or motion holds a NaN or an infinity.
    pub fn first_not_finite(&self) -> Option<usize> {
        (0..self.position.len()).find(|&b| {
            !(self.position[b].is_finite()
                && self.orientation[b].is_finite()
                && self.linear_velocity[b].is_finite()
                && self.angular_momentum[b].is_finite())
        })
    }

    /// State for `model` with every body at `poses`, at rest.
    pub fn at_rest(model: &RigidBodyModel, poses: &[RigidPose]) -> Result<Self, ContactError> {
        if poses.len() != model.len() {
            return Err(ContactError::LengthMismatch { what: "rigid body poses", expected: model.len(), got: poses.len() });
        }
        Ok(RigidBodyState {
            position: poses.iter().map(|p| p.position_m).collect(),
            orientation: poses.iter().map(|p| p.orientation.normalize()).collect(),
            linear_velocity: vec![DVec3::ZERO; poses.len()],
            angular_momentum: vec![DVec3::ZERO; poses.len()],
        })
    }

    pub fn pose(&self, b: usize) -> RigidPose {
        RigidPose { position_m: self.position[b], orientation: self.orientation[b] }
    }

    /// World angular velocity of body `b`, rad/s.
    pub fn angular_velocity(&self, model: &RigidBodyModel, b: usize) -> DVec3 {
        model.inverse_inertia_world(b, self.orientation[b]) * self.angular_momentum[b]
    }

    /// Sets the world angular velocity of body `b` (through its momentum).
    pub fn set_angular_velocity(&mut self, model: &RigidBodyModel, b: usize, omega: DVec3) {
        let r = DMat3::from_quat(self.orientation[b] * model.principal_axes[b]);
        let inertia = DVec3::new(
            safe_recip(model.inverse_principal_inertia[b].x),
            safe_recip(model.inverse_principal_inertia[b].y),
            safe_recip(model.inverse_principal_inertia[b].z),
        );
        self.angular_momentum[b] = r * (inertia * (r.transpose() * omega));
    }

    /// Velocity of the world point `p` carried by body `b`.
    pub fn point_velocity(&self, model: &RigidBodyModel, b: usize, p: DVec3) -> DVec3 {
        self.linear_velocity[b] + self.angular_velocity(model, b).cross(p - self.position[b])
    }

    /// Kinetic energy of body `b`, J.
    pub fn kinetic_energy(&self, model: &RigidBodyModel, b: usize) -> f64 {
        0.5 * model.mass_kg[b] * self.linear_velocity[b].length_squared()
            + 0.5 * self.angular_momentum[b].dot(self.angular_velocity(model, b))
    }

    /// One symplectic Euler step of length `dt`: velocities and momenta take
    /// the wrenches (evaluated by the caller at the current state), then
    /// positions move with the new velocities and orientations follow the
    /// exact principal-axis rotations of the new momenta.
    pub fn step(&mut self, model: &RigidBodyModel, wrenches: &[Wrench], dt: f64) -> Result<(), ContactError> {
        if wrenches.len() != model.len() {
            return Err(ContactError::LengthMismatch { what: "wrenches", expected: model.len(), got: wrenches.len() });
        }
        check_non_negative("dt", dt, false)?;
        for (b, w) in wrenches.iter().enumerate() {
            self.linear_velocity[b] += dt * model.inverse_mass[b] * w.force;
            self.position[b] += dt * self.linear_velocity[b];
            self.angular_momentum[b] += dt * w.torque;
            self.orientation[b] = free_rotation(
                self.orientation[b],
                model.principal_axes[b],
                model.inverse_principal_inertia[b],
                self.angular_momentum[b],
                dt,
            );
        }
        Ok(())
    }
}

fn safe_recip(x: f64) -> f64 {
    if x > 0.0 { 1.0 / x } else { 0.0 }
}

/// Torque-free rotation for `dt` with fixed world momentum `l`, by the
/// symmetric composition 1(h/2) 2(h/2) 3(h) 2(h/2) 1(h/2) of exact rotations
/// about the principal axes.
fn free_rotation(q: DQuat, axes: DQuat, inverse_inertia: DVec3, l: DVec3, dt: f64) -> DQuat {
    let mut principal = q * axes;
    for (axis, h) in [(0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)] {
        let l_principal = principal.inverse() * l;
        let angle = h * dt * l_principal[axis] * inverse_inertia[axis];
        principal *= DQuat::from_axis_angle(DVec3::AXES[axis], angle);
    }
    (principal * axes.inverse()).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn top() -> (RigidBodyModel, RigidBodyState) {
        let mut model = RigidBodyModel::default();
        // An asymmetric body with its principal axes off the body axes.
        let tilt = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.9));
        let inertia = tilt * DMat3::from_diagonal(DVec3::new(1.0e-3, 2.0e-3, 3.5e-3)) * tilt.transpose();
        model.add(MassProperties { mass_kg: 0.6, inertia_kg_m2: inertia, rotation_locked: false }).unwrap();
        let mut state = RigidBodyState::at_rest(&model, &[RigidPose::IDENTITY]).unwrap();
        state.set_angular_velocity(&model, 0, DVec3::new(3.0, 20.0, 1.0));
        (model, state)
    }

    #[test]
    fn torque_free_top_keeps_momentum_and_energy() {
        let (model, mut state) = top();
        let l0 = state.angular_momentum[0];
        let e0 = state.kinetic_energy(&model, 0);
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            state.step(&model, &[Wrench::default()], 1e-3).unwrap();
            worst = worst.max((state.kinetic_energy(&model, 0) - e0).abs() / e0);
        }
        eprintln!("torque-free top: 20000 steps of 1 ms, worst relative energy error {worst:.2e}");
        // Momentum exactly (the torque-free step never touches it).
        assert_eq!(state.angular_momentum[0], l0);
        // Energy: bounded oscillation of order (omega dt)^2, no drift; the
        // body turned about 60 times over the run (20 rad/s for 20 s).
        assert!(worst < 1e-4, "energy error {worst}");
        // The motion did happen (the orientation moved far from the start).
        assert!(state.orientation[0].angle_between(DQuat::IDENTITY) > 0.1);
    }

    #[test]
    fn energy_error_shrinks_with_the_step() {
        let run = |dt: f64| {
            let (model, mut state) = top();
            let e0 = state.kinetic_energy(&model, 0);
            let mut worst = 0.0f64;
            for _ in 0..(2.0 / dt) as usize {
                state.step(&model, &[Wrench::default()], dt).unwrap();
                worst = worst.max((state.kinetic_energy(&model, 0) - e0).abs() / e0);
            }
            worst
        };
        let (coarse, fine) = (run(4e-3), run(2e-3));
        eprintln!("torque-free top: worst energy error {coarse:.2e} at 4 ms, {fine:.2e} at 2 ms");
        // Second order: halving the step quarters the error (within a margin).
        assert!(fine < 0.35 * coarse, "coarse {coarse} fine {fine}");
    }

    #[test]
    fn constant_force_gives_uniform_acceleration() {
        let mut model = RigidBodyModel::default();
        model.add(MassProperties { mass_kg: 2.0, inertia_kg_m2: DMat3::IDENTITY, rotation_locked: false }).unwrap();
        let mut state = RigidBodyState::at_rest(&model, &[RigidPose::IDENTITY]).unwrap();
        let w = Wrench { force: DVec3::new(0.0, 0.0, -19.62), torque: DVec3::ZERO };
        for _ in 0..1000 {
            state.step(&model, &[w], 1e-3).unwrap();
        }
        // Symplectic Euler: x_n = a dt^2 n (n + 1) / 2.
        let expected = -9.81 * 1e-6 * 1000.0 * 1001.0 / 2.0;
        assert!((state.position[0].z - expected).abs() < 1e-12);
        assert!((state.linear_velocity[0].z + 9.81).abs() < 1e-12);
    }

    #[test]
    fn effective_mass_of_a_central_push_is_the_mass() {
        let (model, state) = top();
        let m = model.effective_mass(0, state.orientation[0], DVec3::ZERO, DVec3::X);
        assert!((m - 0.6).abs() < 1e-12);
        assert!(model.effective_mass(0, state.orientation[0], DVec3::new(0.0, 0.05, 0.0), DVec3::X) < 0.6);
        assert!(model.smallest_effective_mass(0, 0.05) <= model.effective_mass(0, state.orientation[0], DVec3::new(0.0, 0.05, 0.0), DVec3::X));
    }

    #[test]
    fn bad_mass_properties_are_refused() {
        let mut model = RigidBodyModel::default();
        let err = model
            .add(MassProperties { mass_kg: 0.0, inertia_kg_m2: DMat3::IDENTITY, rotation_locked: false })
            .unwrap_err();
        assert!(matches!(err, ContactError::InvalidParameter { name: "mass_kg", .. }));
        let err = model
            .add(MassProperties { mass_kg: 1.0, inertia_kg_m2: DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0)), rotation_locked: false })
            .unwrap_err();
        assert!(matches!(err, ContactError::InvalidParameter { name: "inertia_kg_m2", .. }));
    }
}
