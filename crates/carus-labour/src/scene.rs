//! The scene of one run, built once from a scenario: the rigid pelvis (with
//! its contact regions), the fetal head and trunk (in two segments when the
//! spine bends) as rigid bodies (surfaces,
//! contact samples, mass properties from their volumes), the neck geometry,
//! the TLED pelvic floor, and the starting pose. All constant: the mutable
//! state lives in [`crate::sim::SimState`].

use std::path::PathBuf;
use std::sync::Arc;

use carus_analysis::{BirthCanal, ContactSite, HeadGeometry, TrunkGeometry};
use carus_anatomy::fetus::{FetalHead, HeadLandmarks, Trunk};
use carus_anatomy::floor::{pelvic_floor, ATTACHED};
use carus_anatomy::import::MeshReport;
use carus_anatomy::{Pelvis, Plane, TriSurface};
use carus_contact::{
    obstacle_contacts_by_region, pair_contacts, BodyContactState, BodyMotion, ContactLaw, HeadAxes, MassProperties, NeckGeometry, RegionTable,
    NeckRest, RigidBodyModel, RigidObstacle, RigidPose, SoftCover, SurfaceSamples, TriangleCollider, DESIGN_PENETRATION_M,
};
use carus_fem::{BoundaryConditions, Material, MaterialRegion, Mesh, ModelOptions, TledModel};
use glam::{DMat3, DQuat, DVec3};

use crate::scenario::{ContactSection, Presentation, Scenario};
use crate::trajectory::{HeadCoordinates, Mode, Trajectory, TrajectoryPoint};
use crate::LabourError;

/// Index of the head among the rigid bodies.
pub const HEAD: usize = 0;
/// Index of the trunk among the rigid bodies (when there is one): the
/// whole trunk, or its thorax when the spine bends.
pub const TRUNK: usize = 1;
/// Index of the lower trunk among the rigid bodies (when the spine bends).
pub const LOWER_TRUNK: usize = 2;

/// One fetal part as a rigid body: its surface in its centre-of-mass frame,
/// the contact samples on it, and the collider the floor nodes are tested against.
#[derive(Debug)]
pub struct FetalBody {
    pub surface: TriSurface,
    pub samples: SurfaceSamples,
    pub collider: TriangleCollider,
    pub mass: MassProperties,
    /// Where the anatomy's own frame origin lies in the centre-of-mass frame.
    pub frame_origin: DVec3,
}

/// The head as an obstacle to the trunk below its thoracic inlet: the chin
/// meets the chest, and the shoulders meet the skull instead of sliding
/// into it. The neck and throat above the inlet (whose top overlaps the
/// skull base at rest) are the neck joint's, not this contact's.
#[derive(Debug)]
pub struct HeadTrunkContact {
    /// The head's surface in its centre-of-mass frame.
    pub head: RigidObstacle,
    /// The trunk's (or thorax's) samples below its thoracic inlet, in
    /// its centre-of-mass frame.
    pub trunk_samples: SurfaceSamples,
}

/// The pelvic floor's constant data.
#[derive(Debug)]
pub struct FloorScene {
    pub mesh: Mesh,
    pub model: Arc<TledModel>,
    pub bcs: BoundaryConditions,
    /// Reference node positions, pelvis frame.
    pub reference: Vec<DVec3>,
    /// The floor's critical TLED step, s.
    pub critical_step_s: f64,
    /// Per node: fixed to bone (the mesh's attached set). The fetus never
    /// holds these: carus-fem's imposed displacements override fixed dofs,
    /// so a held attachment node would be torn off the bone.
    pub attached: Vec<bool>,
}

/// Everything constant in a run.
#[derive(Debug)]
pub struct Scene {
    pub scenario: Scenario,
    pub pelvis: Pelvis,
    /// What importing the pelvis found in its mesh (holes, triangles turned
    /// outwards), and the mesh's path; `None` for a generated pelvis.
    pub pelvis_import: Option<(MeshReport, PathBuf)>,
    /// A digest of an imported pelvis's files as read (CRC-32 of the
    /// landmarks file and the mesh, hex): what a checkpoint keeps to tell
    /// the pelvis a run started in from one edited since. None for a
    /// generated or built-in pelvis, which the scenario's text fixes.
    pub pelvis_digest: Option<String>,
    /// The sacrospinous ligaments, part of the canal's rigid wall.
    pub ligaments: TriSurface,
    pub canal: BirthCanal,
    pub pelvis_collider: RigidObstacle,
    /// The [`ContactSite`] of each pelvic region label.
    pub sites: Vec<ContactSite>,
    pub head: FetalBody,
    pub head_geometry: HeadGeometry,
    /// Head axes in the head's centre-of-mass frame.
    pub head_axes: HeadAxes,
    /// The atlanto-occipital pivot in the head's centre-of-mass frame.
    pub pivot_in_head: DVec3,
    /// The head's landmarks (fontanelles, eminences, occiput...) in its
    /// centre-of-mass frame, for pictures.
    pub head_landmarks: HeadLandmarks,
    /// The whole trunk, or the thorax when the spine bends.
    pub trunk: Option<FetalBody>,
    /// The shoulders, the trunk's centre and its spine axis, in the frame
    /// of `trunk` (the detector's k: CARDINAL_MOVEMENTS.md, from the pivot
    /// along the spine, so from the segment that carries the head).
    pub trunk_geometry: Option<TrunkGeometry>,
    /// Abdomen and hips, when the spine bends (`[spine]`).
    pub lower_trunk: Option<FetalBody>,
    /// The neck joining head and trunk at the start (when there is a trunk).
    pub neck_joint: Option<NeckGeometry>,
    /// The thoracolumbar joint of thorax and lower trunk at the start
    /// (when the spine bends).
    pub spine_joint: Option<NeckGeometry>,
    /// Spine axis k in the trunk's centre-of-mass frame (and the lower
    /// trunk's: both are the anatomy's trunk frame, moved).
    pub spine_in_trunk: DVec3,
    /// Without a trunk, the spine axis k in the head's centre-of-mass
    /// frame: the neck held at its rest attitude (`Scene::rest_spine_in_head`).
    pub spine_in_head: DVec3,
    pub bodies: RigidBodyModel,
    pub law: ContactLaw,
    /// The trunk's law on bone (softer: the shoulders are soft tissue),
    /// and on the head.
    pub trunk_law: ContactLaw,
    /// Laws of their own on regions of the canal wall, for the head and
    /// the trunk (the ligaments, where `contact.ligament_stiffness_ratio`
    /// makes them softer than bone; none otherwise).
    pub region_laws: [Vec<(u16, ContactLaw)>; 2],
    /// The head against the trunk (`[contact] head_trunk`), when there is a trunk.
    pub head_trunk: Option<HeadTrunkContact>,
    pub floor: Option<FloorScene>,
    /// Starting poses (head, then trunk), pelvis frame.
    pub start: Vec<RigidPose>,
    /// The head's way-points from the start, in the imposed and hybrid
    /// modes only: forward mode has none to read.
    pub trajectory: Option<Trajectory>,
}

impl Scene {
    pub fn build(scenario: &Scenario) -> Result<Scene, LabourError> {
        let (pelvis, pelvis_import) = build_pelvis(scenario)?;
        let canal = BirthCanal::from_pelvis(&pelvis)
            .map_err(|e| LabourError::anatomy(format!("pelvic axis: {e}")))?;
        let ligaments = carus_anatomy::floor::sacrospinous_ligaments(&pelvis, scenario.floor.mesh.sacrospinous_bow);
        let CanalWall { surface: wall, labels, sites } = canal_wall(&pelvis, &ligaments, &scenario.contact);
        let label_of = |wanted: ContactSite| sites.iter().position(|site| *site == wanted).map(|i| i as u16);
        let names = sites.iter().map(|s| s.name().to_string()).collect();
        let pelvis_collider =
            RigidObstacle::new("pelvis", &wall.vertices, &wall.triangles, Some(RegionTable { names, labels }))?;

        let s = scenario;
        let head_anatomy = FetalHead::with_subdivisions(&s.head, &s.fetus.atlanto_occipital(), s.numerics.head_subdivisions)
            .map_err(|e| unbuildable(s, "head", e.diameter_key(), true, e))?;
        let spacing = s.contact.sample_spacing_mm * 1e-3;
        let head = FetalBody::new(
            "head",
            &head_anatomy.surface,
            s.fetus.density_kg_per_m3,
            spacing,
        )?;
        let mut head_geometry = HeadGeometry::from_fetal_head(&head_anatomy);
        head_geometry.centre_m += head.frame_origin;
        for p in &mut head_geometry.skull_points_m {
            *p += head.frame_origin;
        }
        let head_axes = HeadAxes {
            occipitofrontal: DVec3::X,
            vertex: DVec3::Z,
        };
        let pivot_in_head = head_anatomy.landmarks.atlanto_occipital + head.frame_origin;
        let head_landmarks = head_anatomy.landmarks.map(|p| p + head.frame_origin);

        let mut bodies = RigidBodyModel::default();
        bodies.add(head.mass)?;
        let mut lower_trunk = None;
        // The thoracolumbar joint in the thorax's frame.
        let mut thoracolumbar = None;
        let (trunk, trunk_geometry, spine_in_trunk, thoracic_inlet) = if s.trunk.enabled {
            let anatomy =
                Trunk::new(&s.trunk.diameters()).map_err(|e| LabourError::anatomy(format!("fetal trunk: {e}")))?;
            let density = s.fetus.density_kg_per_m3;
            let body = if s.spine.enabled {
                let parts = anatomy.segments();
                let thorax = FetalBody::new("thorax", &parts.thorax, density, spacing)?;
                let lower = FetalBody::new("lower trunk", &parts.lower, density, spacing)?;
                thoracolumbar = Some(parts.thoracolumbar + thorax.frame_origin);
                lower_trunk = Some(lower);
                thorax
            } else {
                FetalBody::new("trunk", &anatomy.surface, density, spacing)?
            };
            let mut g = TrunkGeometry::from_trunk(&anatomy);
            g.centre_m += body.frame_origin;
            g.right_acromion_m += body.frame_origin;
            g.left_acromion_m += body.frame_origin;
            bodies.add(body.mass)?;
            if let Some(lower) = &lower_trunk {
                bodies.add(lower.mass)?;
            }
            (Some(body), Some(g), anatomy.spine_axis, Some(anatomy.thoracic_inlet()))
        } else {
            (None, None, DVec3::NEG_Z, None)
        };

        let law = ContactLaw {
            penalty_stiffness_pa_per_m: s.contact.penalty_stiffness_pa_per_m,
            damping_time_s: s.contact.damping_time_s,
            friction_coefficient: s.contact.friction,
            ..ContactLaw::default()
        };
        law.validate()?;
        let trunk_law = ContactLaw {
            penalty_stiffness_pa_per_m: s.contact.trunk_penalty_stiffness_pa_per_m,
            cover: Some(SoftCover {
                depth_m: s.contact.trunk_cover_depth_mm * 1e-3,
                core_stiffness_pa_per_m: s.contact.penalty_stiffness_pa_per_m,
            }),
            ..law
        };
        trunk_law.validate()?;
        // The ligaments' and soft walls' own laws, where they are softer than bone.
        let softer_sites = [
            (ContactSite::SacrospinousLigament, s.contact.ligament_stiffness_ratio),
            (ContactSite::AbdominalWall, s.contact.soft_wall_stiffness_ratio),
            (ContactSite::ObturatorMembrane, s.contact.soft_wall_stiffness_ratio),
        ];
        let softer_regions = |law: &ContactLaw| -> Vec<(u16, ContactLaw)> {
            softer_sites
                .iter()
                .filter(|(_, ratio)| *ratio < 1.0)
                .filter_map(|&(site, ratio)| {
                    let softer = ContactLaw {
                        penalty_stiffness_pa_per_m: ratio * law.penalty_stiffness_pa_per_m,
                        cover: law.cover.map(|c| SoftCover { core_stiffness_pa_per_m: ratio * c.core_stiffness_pa_per_m, ..c }),
                        ..*law
                    };
                    label_of(site).map(|label| (label, softer))
                })
                .collect()
        };
        let region_laws = [softer_regions(&law), softer_regions(&trunk_law)];
        let head_trunk = match (&trunk, thoracic_inlet) {
            (Some(body), Some(inlet)) if s.contact.head_trunk => Some(HeadTrunkContact::new(&head, body, &inlet)?),
            _ => None,
        };

        let floor = if s.floor.enabled {
            Some(build_floor(scenario, &pelvis)?)
        } else {
            None
        };
        let mut scene = Scene {
            scenario: scenario.clone(),
            pelvis,
            pelvis_digest: pelvis_files_digest(scenario, pelvis_import.as_ref()),
            pelvis_import,
            ligaments,
            canal,
            pelvis_collider,
            sites,
            head,
            head_geometry,
            head_axes,
            pivot_in_head,
            head_landmarks,
            trunk,
            trunk_geometry,
            lower_trunk,
            neck_joint: None,
            spine_joint: None,
            spine_in_trunk,
            spine_in_head: DVec3::ZERO,
            bodies,
            law,
            trunk_law,
            region_laws,
            head_trunk,
            floor,
            start: Vec::new(),
            trajectory: None,
        };
        scene.trajectory = (scenario.trajectory.mode != Mode::Forward)
            .then(|| {
                Trajectory::new(scene.start_coordinates(), &scenario.trajectory.waypoints, |c| scene.centre_sigma_at(c))
            });
        scene.start = scene.start_poses();
        scene.spine_in_head = scene.rest_spine_in_head();
        scene.check_head_not_born()?;
        scene.check_head_clear_of_bone()?;
        scene.check_waypoints_clear_of_bone()?;
        scene.check_head_clear_of_trunk()?;
        scene.neck_joint = scene.trunk.is_some().then(|| NeckGeometry {
            head: HEAD,
            trunk: TRUNK,
            pivot: scene.start_pivot(),
            axes: scene.head_axes,
            neck_axis: -(scene.start[TRUNK].orientation * scene.spine_in_trunk),
            // The start pose puts the trunk at neutral and the head at the
            // scenario's attitude (Scene::start_poses).
            joined_flexion_deg: scenario.start.attitude_deg,
        });
        // The thorax takes the head's place: x ventral, z cranial
        // (carus-anatomy's trunk frame), so flexion bends it forwards.
        scene.spine_joint = thoracolumbar.map(|joint| NeckGeometry {
            head: TRUNK,
            trunk: LOWER_TRUNK,
            pivot: scene.start[TRUNK].point(joint),
            axes: HeadAxes {
                occipitofrontal: DVec3::X,
                vertex: DVec3::Z,
            },
            neck_axis: -(scene.start[LOWER_TRUNK].orientation * scene.spine_in_trunk),
            joined_flexion_deg: 0.0,
        });
        Ok(scene)
    }

    /// Head and trunk at the scenario's start: station of the leading point,
    /// position of the denominator, attitude (all inputs). Forward, both
    /// are turned in the canal's frame at its top; with a trajectory, in
    /// the frame at the head, where the trajectory's own start turns them,
    /// so that the head does not jump at the first step.
    fn start_poses(&self) -> Vec<RigidPose> {
        let start = &self.scenario.start;
        let path_start = self.trajectory.as_ref().map(|path| path.at(0.0));
        let (q_head, q_trunk) = self.start_orientations();
        let head = match path_start {
            Some(p) => self.head_on_trajectory(p),
            None => self.head_at_station(start.station_mm, |_| (q_head, DVec3::ZERO)).0,
        };
        let pivot = head.point(self.pivot_in_head);
        // The trunk frame's origin is the pivot; each segment's centre of
        // mass sits at -frame_origin from it, the spine straight.
        let segment = |b: &FetalBody| RigidPose::new(pivot - q_trunk * b.frame_origin, q_trunk);
        std::iter::once(head)
            .chain(self.trunk.iter().chain(&self.lower_trunk).map(segment))
            .collect()
    }

    /// The head's orientation at the scenario's start, and the trunk's (the
    /// head's at attitude 0, in line with the spine), pelvis frame.
    fn start_orientations(&self) -> (DQuat, DQuat) {
        let path_start = self.trajectory.as_ref().map(|path| path.at(0.0));
        let frame = self.canal.axis().frame(path_start.map_or(0.0, |p| p.centre_sigma_m));
        let occiput_theta = self.start_occiput_theta_deg();
        let orient = |phi: f64| {
            carus_analysis::synthetic::head_orientation(frame.tangent, frame.anterior, frame.transverse, occiput_theta, phi)
        };
        (orient(self.scenario.start.attitude_deg), orient(0.0))
    }

    /// Without a trunk, the spine's direction k in the head frame: the neck
    /// held at its rest attitude (`[neck] rest_attitude`). At the start's
    /// attitude, k is the trunk's spine as it would be joined, so the
    /// head presents as the scenario starts it (phi = the start attitude);
    /// at neutral, k = -vertex (phi = 0).
    fn rest_spine_in_head(&self) -> DVec3 {
        let neutral = -self.head_axes.vertex;
        match self.scenario.neck.rest_attitude {
            NeckRest::Neutral => neutral,
            NeckRest::Start => {
                let (_, q_trunk) = self.start_orientations();
                (self.start[HEAD].orientation.inverse() * (q_trunk * neutral)).normalize()
            }
        }
    }

    /// The head with its leading point at `station_mm`, turned and its
    /// centre moved off the pelvic axis as `off_axis` says for a centre at
    /// a given arc length (m); and that arc length.
    fn head_at_station(&self, station_mm: f64, off_axis: impl Fn(f64) -> (DQuat, DVec3)) -> (RigidPose, f64) {
        let axis = self.canal.axis();
        let target = self.canal.spines_sigma() + station_mm * 1e-3;
        let mut centre_sigma = target - 0.05;
        let centre = self.head_geometry.centre_m;
        let mut placed = (RigidPose::new(DVec3::ZERO, off_axis(centre_sigma).0), centre_sigma);
        for _ in 0..8 {
            let (q, offset) = off_axis(centre_sigma);
            let pose = RigidPose::new(axis.point(centre_sigma) + offset - q * centre, q);
            placed = (pose, centre_sigma);
            if let Some((_, sigma)) =
                self.canal
                    .leading_point(&self.head_geometry.skull_points_m, &pose, centre_sigma)
            {
                centre_sigma += target - sigma;
            }
        }
        placed
    }

    /// The head's pose and orientation at a trajectory's point: the occiput
    /// at theta and the attitude phi in the canal's frame at the head's own
    /// arc length, so that the head turns with the curve of Carus, and its
    /// centre `anterior_mm` off the axis towards the symphysis.
    pub fn head_on_trajectory(&self, point: TrajectoryPoint) -> RigidPose {
        let sigma = point.centre_sigma_m;
        let (q, offset) = self.turned_at(sigma, point.theta_deg, point.phi_deg, point.anterior_mm);
        RigidPose::new(self.canal.axis().point(sigma) + offset - q * self.head_geometry.centre_m, q)
    }

    /// The head's orientation for theta and phi in the canal's frame at arc
    /// length `sigma` (m), and the offset of its centre off the axis.
    fn turned_at(&self, sigma: f64, theta_deg: f64, phi_deg: f64, anterior_mm: f64) -> (DQuat, DVec3) {
        let frame = self.canal.axis().frame(sigma);
        let q = carus_analysis::synthetic::head_orientation(
            frame.tangent,
            frame.anterior,
            frame.transverse,
            theta_deg,
            phi_deg,
        );
        (q, frame.anterior * anterior_mm * 1e-3)
    }

    /// The arc length of the head's centre when its leading point is at
    /// the coordinates' station, the head turned and moved as they say.
    pub fn centre_sigma_at(&self, c: &HeadCoordinates) -> f64 {
        self.head_at_station(c.station_mm, |sigma| self.turned_at(sigma, c.theta_deg, c.phi_deg, c.anterior_mm))
            .1
    }

    /// The start as trajectory coordinates: station, the occiput's theta
    /// (the chin's opposite in a face presentation) and the attitude.
    pub fn start_coordinates(&self) -> HeadCoordinates {
        let start = &self.scenario.start;
        HeadCoordinates {
            station_mm: start.station_mm,
            theta_deg: self.start_occiput_theta_deg(),
            phi_deg: start.attitude_deg,
            anterior_mm: 0.0,
        }
    }

    /// The occiput's theta at the start: the face is named by the chin,
    /// which lies opposite the occiput.
    fn start_occiput_theta_deg(&self) -> f64 {
        let start = &self.scenario.start;
        match start.presentation {
            Presentation::Vertex => start.position.theta_deg(),
            Presentation::Face => start.position.theta_deg() + 180.0,
        }
    }

    /// Refuses a start below the outlet: the head would be born before the
    /// first step (CARDINAL_MOVEMENTS.md: its centre past the outlet
    /// plane), and the run would report a delivery that never happened.
    fn check_head_not_born(&self) -> Result<(), LabourError> {
        let past_mm = self.canal.outlet().signed_distance(self.start[HEAD].position_m) * 1e3;
        if past_mm <= 0.0 {
            return Ok(());
        }
        Err(self
            .scenario
            .refuse(
                "start.station_mm".into(),
                crate::scenario::shown(self.scenario.start.station_mm),
                format!(
                    "the head would start already born, its centre {past_mm:.1} mm past the outlet plane, \
                     so there would be no labour to simulate"
                ),
                "start the head above the outlet (the built-in scenarios start above the inlet, at -55 mm)".into(),
            )
            .into())
    }

    /// Refuses a start where the head already presses into the bony canal
    /// deeper than the bone law's design penetration (started low in the
    /// canal in an attitude that does not fit there): the contact would
    /// throw it out, or let it through, at the first steps.
    fn check_head_clear_of_bone(&self) -> Result<(), LabourError> {
        let found = self.bone_on_head(self.start[HEAD])?;
        if found.deepest_m <= DESIGN_PENETRATION_M {
            return Ok(());
        }
        let site = self.site_name(found.main_region(self.sites.len()));
        let start = &self.scenario.start;
        Err(self
            .scenario
            .refuse(
                "start.station_mm".into(),
                crate::scenario::shown(start.station_mm),
                format!(
                    "the head starts inside the bony canal, {:.1} mm deep at the {site}, more than the \
                     {:.0} mm the contact allows at the start: at this station the canal is narrower \
                     than the head in its starting attitude ({} deg) and position",
                    found.deepest_m * 1e3,
                    DESIGN_PENETRATION_M * 1e3,
                    start.attitude_deg
                ),
                "start the head higher (the built-in scenarios start above the inlet, at -55 mm), \
                 or in an attitude that fits there (start.attitude_deg)"
                    .into(),
            )
            .into())
    }

    /// The bone's contact on a head at rest at `pose`.
    fn bone_on_head(&self, pose: RigidPose) -> Result<carus_contact::ContactReport, LabourError> {
        let samples = &self.fetal_body(HEAD).samples;
        Ok(obstacle_contacts_by_region(
            &self.pelvis_collider,
            self.contact_law(HEAD),
            self.region_laws(HEAD),
            samples,
            &BodyMotion::at_rest(pose),
            pose.position_m,
            &mut BodyContactState::new(samples),
        )?)
    }

    /// Refuses, in imposed mode, a way-point that puts the head into the
    /// bony canal deeper than the contact allows at the start: the run
    /// would stop there (LabourError::TrajectoryThroughBone), so it is
    /// named before the run rather than found after it.
    fn check_waypoints_clear_of_bone(&self) -> Result<(), LabourError> {
        let (Some(path), Mode::Imposed) = (&self.trajectory, self.scenario.trajectory.mode) else {
            return Ok(());
        };
        for (i, w) in self.scenario.trajectory.waypoints.iter().enumerate() {
            let found = self.bone_on_head(self.head_on_trajectory(path.at(w.time_s)))?;
            if found.deepest_m <= DESIGN_PENETRATION_M {
                continue;
            }
            let site = self.site_name(found.main_region(self.sites.len()));
            // Points past the contact's search band carry no depth, so the
            // deepest read is only a floor.
            let depth = format!(
                "at least {:.1} mm (the contact reads depths to {:.0} mm)",
                found.deepest_m * 1e3,
                self.pelvis_collider.search_depth_m() * 1e3
            );
            // Named by its time, the way-point's own key.
            return Err(self
                .scenario
                .refuse(
                    format!("trajectory.waypoints[{i}].time_s"),
                    crate::scenario::shown(w.time_s),
                    format!(
                        "this way-point puts the head {depth} into the bony canal at the {site}, more \
                         than the {:.0} mm the contact allows: at station {} mm the canal is narrower \
                         than the head at theta {} deg, phi {} deg and {} mm off the axis",
                        DESIGN_PENETRATION_M * 1e3,
                        w.station_mm,
                        w.theta_deg,
                        w.phi_deg,
                        w.anterior_mm
                    ),
                    "flex the head more there (phi_deg), turn its occiput along the canal's widest \
                     diameter (theta_deg), or move its centre off the axis away from that wall \
                     (anterior_mm)"
                        .into(),
                )
                .into());
        }
        Ok(())
    }

    /// Refuses a start where the head already presses into the trunk below
    /// its thoracic inlet deeper than the bone law's design penetration (a strongly
    /// flexed attitude puts the chin into the chest, a strongly extended one
    /// the occiput into the back): the contact would throw the two apart at
    /// the first step. Touching (the extended face presentation's occiput on
    /// the back) is allowed.
    fn check_head_clear_of_trunk(&self) -> Result<(), LabourError> {
        let Some(pair) = &self.head_trunk else {
            return Ok(());
        };
        // What the contact would find at the first step, both bodies at rest.
        let mut fresh = BodyContactState::new(&pair.trunk_samples);
        let found = pair_contacts(
            &pair.head,
            &self.trunk_law,
            &pair.trunk_samples,
            &BodyMotion::at_rest(self.start[TRUNK]),
            &BodyMotion::at_rest(self.start[HEAD]),
            &mut fresh,
        )?;
        if found.deepest_m > DESIGN_PENETRATION_M || found.too_deep > 0 {
            let depth = if found.too_deep > 0 {
                "deeper than the contact searches".to_string()
            } else {
                format!("{:.1} mm deep", found.deepest_m * 1e3)
            };
            return Err(self
                .scenario
                .refuse(
                    "start.attitude_deg".into(),
                    crate::scenario::shown(self.scenario.start.attitude_deg),
                    format!(
                        "the head starts inside the trunk below its thoracic inlet, {depth} (the chin in \
                         the chest when flexed, the occiput in the back when extended), more \
                         than the {:.0} mm the contact allows at the start",
                        DESIGN_PENETRATION_M * 1e3
                    ),
                    "bring start.attitude_deg nearer 0, or set contact.head_trunk = false".into(),
                )
                .into());
        }
        Ok(())
    }

    /// How far `head_centre` lies from the pelvic axis (m), when it is
    /// farther than half the inlet's transverse diameter and its nearest
    /// axis point is above the outlet; `None` while it is in the canal. Inside the bony
    /// ring a head centre cannot get that far from the axis without
    /// entering bone (the ring's half-widths are at most that, the head's
    /// radius is over 40 mm); above the inlet it means the fetus has left
    /// the line of the uterus, which the model has no wall to hold (the
    /// fetus can then slide out over the symphysis, outside the pelvis).
    /// A check on the run, not a force.
    pub fn outside_canal(&self, head_centre: DVec3) -> Option<f64> {
        let axis = self.canal.axis();
        let sigma = axis.project(head_centre);
        if sigma >= self.canal.outlet_sigma() {
            return None;
        }
        let l = &self.pelvis.landmarks;
        let half_inlet = 0.5 * (l.iliopectineal_right - l.iliopectineal_left).length();
        let off = (head_centre - axis.point(sigma)).length();
        (off > half_inlet).then_some(off)
    }

    /// The soft walls in the canal's wall, as one surface (the abdominal
    /// wall, then the obturator membranes, each as `[contact]` asks):
    /// `None` when there are none (both off, or an imported pelvis).
    pub fn soft_walls(&self) -> Option<TriSurface> {
        let mut surface = TriSurface::default();
        for (sheet, _) in soft_walls_on(&self.pelvis, &self.scenario.contact) {
            surface.append(sheet);
        }
        (!surface.triangles.is_empty()).then_some(surface)
    }

    /// Rigid body `b`: the head, the trunk (or thorax), the lower trunk.
    pub fn fetal_body(&self, b: usize) -> &FetalBody {
        match b {
            HEAD => &self.head,
            TRUNK => self.trunk.as_ref().expect("a trunk body"),
            _ => self.lower_trunk.as_ref().expect("a lower trunk body"),
        }
    }

    /// The name of the canal site a contact's region label stands for
    /// ("bone" where the label is missing).
    pub fn site_name(&self, region: Option<u16>) -> &'static str {
        region.and_then(|r| self.sites.get(r as usize)).map_or("bone", |s| s.name())
    }

    /// The contact law of body `b` on bone.
    pub fn contact_law(&self, b: usize) -> &ContactLaw {
        if b == HEAD {
            &self.law
        } else {
            &self.trunk_law
        }
    }

    /// Body `b`'s laws of their own on regions of the canal wall.
    pub fn region_laws(&self, b: usize) -> &[(u16, ContactLaw)] {
        &self.region_laws[usize::from(b != HEAD)]
    }

    /// Whether the expulsion force acts at the neck's pivot (no trunk, or
    /// `expulsion.acts_on = "pivot"`) rather than on the breech's body.
    pub fn expulsion_at_pivot(&self) -> bool {
        self.trunk.is_none() || self.scenario.expulsion.acts_on == crate::scenario::ActsOn::Pivot
    }

    /// The body the expulsion pushes when it acts on the trunk: the
    /// segment with the breech.
    pub fn breech_body(&self) -> usize {
        if self.lower_trunk.is_some() {
            LOWER_TRUNK
        } else {
            TRUNK
        }
    }

    /// The pivot of the neck in the pelvis frame at the start.
    pub fn start_pivot(&self) -> DVec3 {
        self.start[HEAD].point(self.pivot_in_head)
    }
}

impl HeadTrunkContact {
    /// The head's surface as the obstacle, and the samples of `trunk`
    /// below its `thoracic_inlet` (in the anatomy's trunk frame).
    fn new(head: &FetalBody, trunk: &FetalBody, thoracic_inlet: &Plane) -> Result<Self, LabourError> {
        Ok(HeadTrunkContact {
            head: RigidObstacle::new("head", &head.surface.vertices, &head.surface.triangles, None)?,
            trunk_samples: trunk.samples.filtered(|p| thoracic_inlet.signed_distance(p - trunk.frame_origin) > 0.0),
        })
    }
}

impl FetalBody {
    fn new(
        what: &'static str,
        surface: &TriSurface,
        density: f64,
        spacing: f64,
    ) -> Result<FetalBody, LabourError> {
        let (mass, com, inertia) = solid_properties(surface, density);
        if mass.is_nan() || mass <= 0.0 {
            return Err(LabourError::anatomy(format!(
                "the {what} surface encloses no volume (is it inside out?)"
            )));
        }
        let vertices: Vec<DVec3> = surface.vertices.iter().map(|v| *v - com).collect();
        let moved = TriSurface::new(vertices, surface.triangles.clone());
        let samples =
            SurfaceSamples::with_spacing(what, &moved.vertices, &moved.triangles, spacing)?;
        let collider = TriangleCollider::new(what, &moved.vertices, &moved.triangles)?;
        Ok(FetalBody {
            surface: moved,
            samples,
            collider,
            mass: MassProperties {
                mass_kg: mass,
                inertia_kg_m2: inertia,
                rotation_locked: false,
            },
            frame_origin: -com,
        })
    }
}

/// Mass, centre of mass and inertia about it of a closed surface filled with
/// uniform density (signed tetrahedra from the origin; Tonon 2004).
pub fn solid_properties(surface: &TriSurface, density: f64) -> (f64, DVec3, DMat3) {
    let mut volume = 0.0;
    let mut first = DVec3::ZERO;
    // Second moments: integral of x_i x_j over the solid.
    let mut second = [[0.0f64; 3]; 3];
    for t in 0..surface.triangles.len() {
        let [a, b, c] = surface.corners(t);
        let v = a.dot(b.cross(c)) / 6.0;
        volume += v;
        first += v * (a + b + c) / 4.0;
        let p = [a, b, c];
        for i in 0..3 {
            for j in 0..3 {
                let mut s = 0.0;
                for k in 0..3 {
                    for l in 0..3 {
                        s += p[k][i] * p[l][j] * if k == l { 2.0 } else { 1.0 };
                    }
                }
                second[i][j] += v * s / 20.0;
            }
        }
    }
    let mass = density * volume;
    let com = first / volume;
    let m = |i: usize, j: usize| density * second[i][j] - mass * com[i] * com[j];
    let trace = m(0, 0) + m(1, 1) + m(2, 2);
    let inertia = DMat3::from_cols_array(&[
        trace - m(0, 0),
        -m(1, 0),
        -m(2, 0),
        -m(0, 1),
        trace - m(1, 1),
        -m(2, 1),
        -m(0, 2),
        -m(1, 2),
        trace - m(2, 2),
    ]);
    (mass, com, inertia)
}

/// [`Scene::pelvis_digest`] of the files an imported pelvis was built from.
fn pelvis_files_digest(s: &Scenario, import: Option<&(MeshReport, PathBuf)>) -> Option<String> {
    let (carus_anatomy::pelvis::PelvisSpec::Imported { landmarks_file }, Some((_, mesh))) = (&s.pelvis, import) else {
        return None;
    };
    if landmarks_file.as_os_str() == carus_anatomy::pelvis::VISIBLE_HUMAN_FEMALE {
        return None;
    }
    let mut digest = crc32fast::Hasher::new();
    for file in [s.base_dir.join(landmarks_file), mesh.clone()] {
        digest.update(&carus_io::input::read_bytes(&file).ok()?);
    }
    Some(format!("{:08x}", digest.finalize()))
}

/// The pelvis, and for an imported one what its import found in the mesh
/// and the mesh's path.
fn build_pelvis(s: &Scenario) -> Result<(Pelvis, Option<(MeshReport, PathBuf)>), LabourError> {
    s.pelvis
        .build_with_report(&s.base_dir)
        .map_err(|e| unbuildable(s, "pelvis", e.diameter_key(), e.of_diameters(), e))
}

/// A scenario's `[pelvis]` or `[head]` table that cannot be built, at the
/// line of the `key` it names where the file writes it, with the keys it
/// names that the file left to their defaults (only for a table of
/// diameters: an import's errors quote its landmarks file, not the table),
/// and the command that builds and measures it without a run.
fn unbuildable(s: &Scenario, table: &str, key: Option<&str>, from_diameters: bool, e: impl std::fmt::Display) -> LabourError {
    let e = e.to_string();
    let note = from_diameters.then(|| s.defaults_note(table, &e)).flatten();
    let defaults = note.map_or(String::new(), |note| format!("\n  note: {note}"));
    LabourError::Anatomy {
        at: key.map_or(String::new(), |key| s.located_key(&format!("{table}.{key}"))),
        message: format!(
            "[{table}]: {e}{defaults}\n  hint: `carus measure {table} FILE` builds the {table} of a scenario \
             file and prints every diameter without running; `carus scenarios show normal` gives a \
             set that builds"
        ),
    }
}

fn build_floor(s: &Scenario, pelvis: &Pelvis) -> Result<FloorScene, LabourError> {
    let mesh = pelvic_floor(pelvis, &s.floor.mesh).map_err(|e| {
        let at = e.key().map_or(String::new(), |key| s.located_key(&format!("floor.mesh.{key}")));
        LabourError::Anatomy { at, message: format!("pelvic floor ([floor.mesh] in the scenario): {e}") }
    })?;
    let material = Material::neo_hookean(s.floor.shear_modulus_pa, s.floor.bulk_modulus_pa);
    let region = MaterialRegion {
        element_set: None,
        material,
        density_kg_m3: s.floor.density_kg_per_m3,
    };
    let options = ModelOptions {
        damping_per_s: s.floor.damping_per_s,
        hourglass_coefficient: s.floor.hourglass_coefficient,
        hourglass_modulus: s.floor.hourglass_modulus,
        ..ModelOptions::default()
    };
    let model = Arc::new(TledModel::new(&mesh, &[region], &options)?);
    let mut bcs = BoundaryConditions::default();
    let attached = mesh
        .node_sets
        .get(ATTACHED)
        .ok_or_else(|| LabourError::anatomy("pelvic floor has no attached node set"))?;
    bcs.fix_nodes(attached);
    let mut is_attached = vec![false; mesh.nodes.len()];
    for &n in attached {
        if let Some(a) = is_attached.get_mut(n as usize) {
            *a = true;
        }
    }
    let reference = mesh.nodes.iter().map(|p| DVec3::from_array(*p)).collect();
    let critical_step_s = model.critical_time_step();
    Ok(FloorScene {
        mesh,
        model,
        bcs,
        reference,
        critical_step_s,
        attached: is_attached,
    })
}

/// The rigid wall of the canal: the bone, the sacrospinous ligaments that
/// close it behind the side walls below the spines, and (as `contact`
/// asks) the abdominal wall and obturator membranes that close its other openings,
/// with a site label per triangle and the sites the labels index.
struct CanalWall {
    surface: TriSurface,
    labels: Vec<u16>,
    sites: Vec<ContactSite>,
}

fn canal_wall(pelvis: &Pelvis, ligaments: &TriSurface, contact: &ContactSection) -> CanalWall {
    let (mut labels, mut sites) = regions(pelvis);
    let mut surface = pelvis.surface.clone();
    let sheets = std::iter::once((ligaments, ContactSite::SacrospinousLigament)).chain(soft_walls_on(pelvis, contact));
    for (sheet, site) in sheets.filter(|(sheet, _)| !sheet.triangles.is_empty()) {
        surface.append(sheet);
        labels.resize(surface.triangles.len(), sites.len() as u16);
        sites.push(site);
    }
    CanalWall { surface, labels, sites }
}

/// The pelvis's soft walls that `[contact]` puts in the canal's wall, with
/// their sites: the abdominal wall, then the obturator membranes.
fn soft_walls_on<'a>(pelvis: &'a Pelvis, contact: &ContactSection) -> impl Iterator<Item = (&'a TriSurface, ContactSite)> {
    let walls = &pelvis.soft_walls;
    [
        (&walls.abdominal_wall, ContactSite::AbdominalWall, contact.abdominal_wall),
        (&walls.obturator_membranes, ContactSite::ObturatorMembrane, contact.obturator_membranes),
    ]
    .into_iter()
    .filter_map(|(sheet, site, on)| on.then_some((sheet, site)))
}

/// Labels each pelvis triangle with the part of the bony canal it belongs
/// to: the nearest landmark group to its centroid (symphysis, pubic arch,
/// promontory, sacrum, coccyx, spines, side wall). The sacrospinous
/// ligaments and the floor are sites of their own.
fn regions(pelvis: &Pelvis) -> (Vec<u16>, Vec<ContactSite>) {
    let l = &pelvis.landmarks;
    let sites = vec![
        ContactSite::Symphysis,
        ContactSite::PubicArch,
        ContactSite::SacralPromontory,
        ContactSite::Sacrum,
        ContactSite::Coccyx,
        ContactSite::IschialSpines,
        ContactSite::PelvicSidewall,
    ];
    let anchors: Vec<(DVec3, u16)> = vec![
        (l.symphysis_upper, 0),
        (l.symphysis_lower, 0),
        (l.symphysis_middle(), 0),
        (l.ischial_tuberosity_left, 1),
        (l.ischial_tuberosity_right, 1),
        (0.5 * (l.symphysis_lower + l.ischial_tuberosity_left), 1),
        (0.5 * (l.symphysis_lower + l.ischial_tuberosity_right), 1),
        (l.sacral_promontory, 2),
        (l.sacrum_s2_s3, 3),
        (l.sacrum_s4_s5, 3),
        (l.coccyx_tip, 4),
        (l.ischial_spine_left, 5),
        (l.ischial_spine_right, 5),
        (l.iliopectineal_left, 6),
        (l.iliopectineal_right, 6),
    ];
    let labels = (0..pelvis.surface.triangles.len())
        .map(|t| {
            let [a, b, c] = pelvis.surface.corners(t);
            let centroid = (a + b + c) / 3.0;
            anchors
                .iter()
                .min_by(|x, y| {
                    (x.0 - centroid)
                        .length_squared()
                        .total_cmp(&(y.0 - centroid).length_squared())
                })
                .map_or(6, |a| a.1)
        })
        .collect();
    (labels, sites)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The head at the normal start touches the trunk nowhere below the
    /// thoracic inlet; turned about the pivot towards flexion, its chin enters the
    /// chest, and the contact turns it back (a moment against flexion about
    /// the pivot) and pushes the trunk away. Extended to the face
    /// presentation's attitude, the occiput at most touches the back.
    #[test]
    fn the_chin_meets_the_chest_and_the_contact_resists_flexion() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        let scene = Scene::build(&s).unwrap();
        let pair = scene.head_trunk.as_ref().expect("on by default");
        let frame = scene.canal.axis().frame(0.0);
        let theta = s.start.position.theta_deg();
        let orient = |phi: f64| carus_analysis::synthetic::head_orientation(frame.tangent, frame.anterior, frame.transverse, theta, phi);
        let pivot = scene.start_pivot();
        let still = carus_contact::BodyMotion::at_rest;
        let trunk = still(scene.start[TRUNK]);
        let contact_at = |phi: f64| {
            let q = orient(phi);
            let head = still(RigidPose::new(pivot - q * scene.pivot_in_head, q));
            let mut memory = carus_contact::BodyContactState::new(&pair.trunk_samples);
            let r = carus_contact::pair_contacts(&pair.head, &scene.trunk_law, &pair.trunk_samples, &trunk, &head, &mut memory).unwrap();
            (r, head.pose.position_m)
        };
        assert_eq!(contact_at(s.start.attitude_deg).0.active, 0);
        // The axis that turns the head towards flexion (phi up).
        let (axis, _) = (orient(41.0) * orient(40.0).inverse()).to_axis_angle();
        // The chin first meets the chest near phi 62 deg (with the measured
        // 37 mm neck; 45 deg with the 24 mm estimated before), well past the
        // neck's 19 deg of flexion in labour.
        assert_eq!(contact_at(60.0).0.active, 0);
        let (r, centre) = contact_at(75.0);
        assert!(r.active > 10 && r.too_deep == 0, "{r:?}");
        let about_pivot = r.on_obstacle.torque + (centre - pivot).cross(r.on_obstacle.force);
        assert!(about_pivot.dot(axis) < -0.2, "{about_pivot} about {axis}");
        assert!(r.on_sampled.force.dot(r.on_obstacle.force) < 0.0);
        assert!(contact_at(-80.0).0.deepest_m < DESIGN_PENETRATION_M);
    }

    /// Without a trunk, the push leaves the head where the trunk's spine
    /// would at the start (the neck at rest in the start's attitude, the
    /// default), so the head presents at its start attitude; with the neck
    /// at rest in neutral, along its vertex.
    #[test]
    fn a_trunkless_head_is_pushed_at_the_necks_rest_attitude() {
        for name in ["normal", "face"] {
            let mut s = Scenario::builtin(name).unwrap();
            s.numerics.head_subdivisions = 3;
            s.floor.enabled = false;
            let with_trunk = Scene::build(&s).unwrap();
            let trunk_spine = with_trunk.start[TRUNK].orientation * with_trunk.spine_in_trunk;
            s.trunk.enabled = false;
            let scene = Scene::build(&s).unwrap();
            let head = scene.start[HEAD].orientation;
            let spine = head * scene.spine_in_head;
            assert!(spine.angle_between(trunk_spine) < 1e-9, "{name}: {spine} against the trunk's {trunk_spine}");
            let attitude = (head * scene.head_axes.vertex).angle_between(-spine).to_degrees();
            assert!((attitude - s.start.attitude_deg.abs()).abs() < 1e-6, "{name}: {attitude} deg");
            s.neck.rest_attitude = NeckRest::Neutral;
            assert_eq!(Scene::build(&s).unwrap().spine_in_head, -scene.head_axes.vertex, "{name}");
        }
    }

    /// Every built-in scenario starts with its head clear of its trunk
    /// (the face presentation's occiput only touching the back).
    #[test]
    fn every_builtin_starts_with_the_head_clear_of_the_trunk() {
        for (name, _) in crate::scenario::BUILTINS {
            let mut s = Scenario::builtin(name).unwrap();
            s.numerics.head_subdivisions = 3;
            s.floor.enabled = false;
            let scene = Scene::build(&s).unwrap_or_else(|e| panic!("{name}: {e}"));
            let pair = scene.head_trunk.as_ref().unwrap_or_else(|| panic!("{name}: no head-trunk contact"));
            let mut memory = BodyContactState::new(&pair.trunk_samples);
            let (trunk, head) = (BodyMotion::at_rest(scene.start[TRUNK]), BodyMotion::at_rest(scene.start[HEAD]));
            let found = pair_contacts(&pair.head, &scene.trunk_law, &pair.trunk_samples, &trunk, &head, &mut memory).unwrap();
            if s.start.attitude_deg < -45.0 {
                assert!(found.too_deep == 0 && found.deepest_m < DESIGN_PENETRATION_M, "{name}: {found:?}");
            } else {
                assert_eq!(found.active, 0, "{name}: {found:?}");
            }
        }
    }

    /// A start with the chin already in the chest is refused, naming the
    /// key and both ways out; off, the same start builds.
    #[test]
    fn a_start_with_the_chin_in_the_chest_is_refused() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.start.attitude_deg = 80.0;
        let e = Scene::build(&s).expect_err("refused").to_string();
        for part in ["start.attitude_deg = 80", "inside the trunk", "contact.head_trunk = false"] {
            assert!(e.contains(part), "{e}");
        }
        s.contact.head_trunk = false;
        assert!(Scene::build(&s).unwrap().head_trunk.is_none());
    }

    /// A start with the head already pressed into the bone is refused,
    /// naming the key, the site and the way out; a few mm higher it builds.
    #[test]
    fn a_start_with_the_head_in_the_bone_is_refused() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.floor.enabled = false;
        s.contact.head_trunk = false;
        s.neck.flexion_limit_deg = 66.0;
        s.start.attitude_deg = 60.0;
        s.start.station_mm = 60.0;
        let e = Scene::build(&s).expect_err("refused").to_string();
        for part in ["start.station_mm = 60", "the head starts inside the bony canal", "deep at the sacrospinous_ligament", "start the head higher"] {
            assert!(e.contains(part), "{e}");
        }

        // Read from a file, the key's line is named; once changed by a
        // setting, the setting is.
        let (file, line) = s.as_read_from("mine.toml", "station_mm = 60");
        let e = Scene::build(&file).expect_err("refused").to_string();
        assert!(e.starts_with(&format!("mine.toml:{line}: `start.station_mm` = 60: the head starts")), "{e}");
        let e = Scene::build(&file.with_setting("start.station_mm", "61").unwrap()).expect_err("refused").to_string();
        assert!(e.starts_with("`start.station_mm = 61`: the head starts"), "{e}");
        // Another key set, the file's start is named at its line with the setting.
        let e = Scene::build(&file.with_setting("neck.flexion_limit_deg", "67").unwrap()).expect_err("refused").to_string();
        assert!(e.starts_with(&format!("mine.toml:{line}: `start.station_mm` = 60: with neck.flexion_limit_deg = 67 set, the head starts")), "{e}");
        // A built-in's start, never set, is refused under what was set.
        let setting = |k: &str, v: &str| (k.to_string(), v.to_string());
        let larger = Scenario::builtin("normal").unwrap().with_settings(&[setting("numerics.head_subdivisions", "3"), setting("head.biparietal_mm", "200")]).unwrap();
        let e = Scene::build(&larger).expect_err("refused").to_string();
        assert!(e.starts_with("`numerics.head_subdivisions = 3, head.biparietal_mm = 200`: then `start.station_mm` = -55, the scenario's own value: the head starts inside the bony canal"), "{e}");
        assert!(e.contains("hint: start the head higher"), "{e}");
        // A key set again (a sweep's value over a mended file's) is named with its last value.
        let again = larger.with_setting("head.biparietal_mm", "210").unwrap();
        let e = Scene::build(&again).expect_err("refused").to_string();
        assert!(e.starts_with("`numerics.head_subdivisions = 3, head.biparietal_mm = 210`: then"), "{e}");
        s.start.station_mm = 45.0;
        assert!(Scene::build(&s).is_ok());
    }

    /// A start below the outlet is refused: the head would be born before
    /// the first step.
    #[test]
    fn a_head_started_below_the_outlet_is_refused() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.start.station_mm = 200.0;
        let e = Scene::build(&s).expect_err("refused").to_string();
        assert!(e.starts_with("`start.station_mm = 200`: the head would start already born, its centre "), "{e}");
        assert!(e.contains("mm past the outlet plane") && e.contains("start the head above the outlet"), "{e}");
    }

    /// A floor that cannot be built names its table, its key and a fix.
    #[test]
    fn a_bad_floor_shape_names_its_key_and_a_fix() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.floor.mesh.bowl_mm = f64::NAN;
        let e = Scene::build(&s).expect_err("refused").to_string();
        for part in ["[floor.mesh]", "bowl_mm", "dome"] {
            assert!(e.contains(part), "{e}");
        }
        // Read from a file, the key's line leads the message.
        s.floor.mesh.bowl_mm = -10.0;
        let (file, line) = s.with_setting("floor.mesh.hiatus_width_mm", "90").unwrap().as_read_from("wide.toml", "hiatus_width_mm = 90");
        let e = Scene::build(&file).expect_err("refused").to_string();
        assert!(e.starts_with(&format!("wide.toml:{line}: anatomy: pelvic floor ([floor.mesh] in the scenario): hiatus_width_mm = 90")), "{e}");
    }

    /// Below 1, `contact.ligament_stiffness_ratio` gives the head and the
    /// trunk laws of their own on the ligaments' region, their stiffnesses
    /// (the trunk's cover and core alike) scaled; at 1, none.
    #[test]
    fn softer_ligaments_get_laws_of_their_own() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.floor.enabled = false;
        let rigid = Scene::build(&s).unwrap();
        assert!(rigid.region_laws(HEAD).is_empty() && rigid.region_laws(TRUNK).is_empty());
        s.contact.ligament_stiffness_ratio = 0.1;
        let scene = Scene::build(&s).unwrap();
        let label = (0..32).find(|&l| scene.pelvis_collider.region_name(l) == Some("sacrospinous_ligament")).expect("a region");
        let [(head_label, head), (trunk_label, trunk)] = [scene.region_laws(HEAD), scene.region_laws(TRUNK)].map(|laws| laws[0]);
        assert_eq!((head_label, trunk_label), (label, label));
        assert_eq!(head.penalty_stiffness_pa_per_m, 0.1 * scene.law.penalty_stiffness_pa_per_m);
        assert_eq!(trunk.penalty_stiffness_pa_per_m, 0.1 * scene.trunk_law.penalty_stiffness_pa_per_m);
        let (cover, bone_cover) = (trunk.cover.unwrap(), scene.trunk_law.cover.unwrap());
        assert_eq!(cover.core_stiffness_pa_per_m, 0.1 * bone_cover.core_stiffness_pa_per_m);
        assert_eq!((cover.depth_m, head.friction_coefficient), (bone_cover.depth_m, scene.law.friction_coefficient));
    }

    /// Diameters that cannot be built lead with the line of the key to
    /// change, read from a file: the pelvis's, and the head's.
    #[test]
    fn unbuildable_diameters_name_their_line() {
        let s = Scenario::builtin("normal").unwrap();
        let (file, line) = s.with_setting("pelvis.mid_posterior_share", "0.05").unwrap().as_read_from("shape.toml", "mid_posterior_share = 0.05");
        let e = Scene::build(&file).expect_err("refused").to_string();
        assert!(e.starts_with(&format!("shape.toml:{line}: anatomy: [pelvis]: mid_posterior_share = 0.05 is outside 0.2 to 0.7")), "{e}");
        let (file, line) = s.with_setting("head.bitemporal_mm", "99").unwrap().as_read_from("head.toml", "bitemporal_mm = 99");
        let e = Scene::build(&file).expect_err("refused").to_string();
        assert!(e.starts_with(&format!("head.toml:{line}: anatomy: [head]: bitemporal_mm (99 mm) must be shorter than biparietal_mm")), "{e}");
    }

    /// A landmarks file that cannot be read is quoted as its own error: its
    /// `name = value` lines are not the scenario's keys left to defaults.
    #[test]
    fn a_broken_landmarks_file_is_not_taken_for_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/anatomy/visible-human-female-pelvis.landmarks.toml");
        let text = std::fs::read_to_string(shipped).unwrap().replace("units = \"mm\"", "units = mm");
        std::fs::write(dir.path().join("broken.landmarks.toml"), text).unwrap();
        let scenario = dir.path().join("scenario.toml");
        std::fs::write(&scenario, "name = \"broken\"\n[pelvis]\nimport = \"broken.landmarks.toml\"\n").unwrap();
        let e = Scene::build(&Scenario::from_file(&scenario).unwrap()).expect_err("refused").to_string();
        assert!(e.contains("broken.landmarks.toml") && e.contains("units = mm"), "{e}");
        assert!(!e.contains("the default"), "{e}");
    }

    /// The floor's hourglass control is the scenario's, not a constant of
    /// the scene: both keys reach its TLED model.
    #[test]
    fn the_floor_model_takes_the_scenarios_hourglass_control() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.floor.hourglass_coefficient = 0.2;
        s.floor.hourglass_modulus = carus_fem::HourglassModulus::Shear;
        let scene = Scene::build(&s).unwrap();
        let options = scene.floor.as_ref().unwrap().model.options();
        assert_eq!(options.hourglass_coefficient, 0.2);
        assert_eq!(options.hourglass_modulus, carus_fem::HourglassModulus::Shear);
    }

    /// The head lever is the scenario's: `[fetus]`'s pivot keys move the
    /// pivot the neck and trunk hang from, towards the occiput, and the
    /// trunk starts hanging from it.
    #[test]
    fn the_neck_pivot_is_placed_by_the_scenario() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.floor.enabled = false;
        let default = Scene::build(&s).unwrap();
        s.fetus.atlanto_occipital_behind_deg = 30.0;
        let back = Scene::build(&s).unwrap();
        let (p, q) = (default.pivot_in_head, back.pivot_in_head);
        let centre = default.head_geometry.centre_m;
        assert!(q.x < p.x, "{q} is not nearer the occiput than {p}");
        let behind = |v: DVec3| (-(v - centre).x).atan2(-(v - centre).z).to_degrees();
        assert!((behind(p) - 15.0).abs() < 1e-9 && (behind(q) - 30.0).abs() < 1e-9);
        assert_eq!(back.neck_joint.unwrap().pivot, back.start_pivot());
        assert_ne!(back.start[TRUNK], default.start[TRUNK]);
    }

    /// A spine that bends cuts the trunk in two at the thoracolumbar joint:
    /// the segments weigh what the whole trunk did, start joined at the
    /// joint with the spine straight, and the shoulders ride on the thorax.
    #[test]
    fn a_bending_spine_cuts_the_trunk_at_the_thoracolumbar_joint() {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.floor.enabled = false;
        let whole = Scene::build(&s).unwrap();
        s.spine.enabled = true;
        let cut = Scene::build(&s).unwrap();
        assert_eq!((whole.bodies.len(), cut.bodies.len()), (2, 3));
        let mass = |scene: &Scene| scene.bodies.mass_kg[TRUNK..].iter().sum::<f64>();
        assert!((mass(&cut) - mass(&whole)).abs() < 1e-9 * mass(&whole));
        assert_eq!(cut.breech_body(), LOWER_TRUNK);
        assert_eq!(whole.breech_body(), TRUNK);
        // One point of the joint for both segments at the start, on the
        // spine line below the chest.
        let joint = cut.spine_joint.unwrap().pivot;
        let lower = cut.lower_trunk.as_ref().unwrap();
        let in_lower = cut.start[LOWER_TRUNK].inverse_point(joint);
        let in_anatomy = in_lower - lower.frame_origin;
        assert!(in_anatomy.x.abs() < 1e-9 && in_anatomy.y.abs() < 1e-9 && in_anatomy.z < -0.1, "{in_anatomy}");
        assert_eq!(cut.start[TRUNK].orientation, cut.start[LOWER_TRUNK].orientation);
        // The acromions (trunk geometry, thorax frame) lie inside the thorax's extent.
        let g = cut.trunk_geometry.as_ref().unwrap();
        let (lo, hi) = cut.trunk.as_ref().unwrap().surface.bounds().unwrap();
        for p in [g.left_acromion_m, g.right_acromion_m] {
            assert!(p.cmpge(lo - 1e-9).all() && p.cmple(hi + 1e-9).all(), "{p} outside {lo}..{hi}");
        }
    }

    /// The normal scene with a coarse head and no floor: the canal alone.
    fn coarse_normal_without_floor() -> Scene {
        let mut s = Scenario::builtin("normal").unwrap();
        s.numerics.head_subdivisions = 3;
        s.contact.sample_spacing_mm = 8.0;
        s.floor.enabled = false;
        Scene::build(&s).unwrap()
    }

    #[test]
    fn a_head_over_the_symphysis_is_outside_the_canal() {
        let scene = coarse_normal_without_floor();
        // The start: on the axis above the inlet.
        assert_eq!(scene.outside_canal(scene.start[HEAD].position_m), None);
        // Along the axis at the spines and just above the outlet: inside.
        let axis = scene.canal.axis();
        for sigma in [
            0.0,
            scene.canal.spines_sigma(),
            scene.canal.outlet_sigma() - 0.01,
        ] {
            assert_eq!(
                scene.outside_canal(axis.point(sigma)),
                None,
                "sigma {sigma}"
            );
        }
        // 135 mm in front of the inlet's centre and 30 mm above it (where
        // the face run's head went when it rode over the symphysis): outside.
        let over = DVec3::new(0.0, 0.135, 0.03);
        let off = scene.outside_canal(over).expect("outside");
        assert!(off > 0.1, "{off}");
        // Past the outlet the head may swing forward as it extends: no check.
        let frame = axis.frame(scene.canal.outlet_sigma() + 0.03);
        assert_eq!(
            scene.outside_canal(frame.point + 0.08 * frame.anterior),
            None
        );
    }

    #[test]
    fn the_sacrospinous_ligaments_stop_the_fetus_where_the_bone_is_open() {
        let scene = coarse_normal_without_floor();
        let bare = ContactSection { abdominal_wall: false, obturator_membranes: false, ..ContactSection::default() };
        let wall = canal_wall(&scene.pelvis, &scene.ligaments, &bare);
        let bone = scene.pelvis.surface.triangles.len();
        assert!(wall.surface.triangles.len() > bone);
        let collider = canal_collider(&wall);
        for t in bone..wall.surface.triangles.len() {
            assert_eq!(wall.sites[wall.labels[t] as usize], ContactSite::SacrospinousLigament);
        }
        // Each ligament's widest face, 2 mm beyond it on the outside: inside
        // the wall, on the ligament, and at least a centimetre from any bone.
        let per_side = (wall.surface.triangles.len() - bone) / 2;
        for t in [bone + 1, bone + per_side + 1] {
            let [a, b, c] = wall.surface.corners(t);
            // Faces wind counter-clockwise seen from the canal.
            let into_canal = (b - a).cross(c - a).normalize();
            let behind = (a + b + c) / 3.0 - 0.002 * into_canal;
            let hit = collider.closest_point(behind, 0.01).unwrap();
            assert!((hit.signed_distance + 0.002).abs() < 1e-4, "{hit:?}");
            assert!(hit.triangle as usize >= bone);
            let to_bone = scene.pelvis.surface.vertices.iter().map(|v| (*v - behind).length()).fold(f64::MAX, f64::min);
            assert!(to_bone > 0.01, "{to_bone}");
        }
    }

    /// The collider of a canal wall, as the scene builds it.
    fn canal_collider(wall: &CanalWall) -> carus_contact::TriangleCollider {
        carus_contact::TriangleCollider::new("pelvis", &wall.surface.vertices, &wall.surface.triangles).unwrap()
    }

    /// The soft walls close the front of the false pelvis and the obturator
    /// foramina, facing the canal: a point just behind either is inside
    /// the wall, on it, and where the bone alone leaves the canal open.
    #[test]
    fn the_soft_walls_close_the_front_of_the_false_pelvis_and_the_obturator_foramina() {
        let scene = coarse_normal_without_floor();
        let walls = &scene.pelvis.soft_walls;
        let both = ContactSection { abdominal_wall: true, obturator_membranes: true, ..ContactSection::default() };
        let neither = ContactSection { abdominal_wall: false, obturator_membranes: false, ..both };
        let with = canal_wall(&scene.pelvis, &scene.ligaments, &both);
        let without = canal_wall(&scene.pelvis, &scene.ligaments, &neither);
        let (closed, open) = (canal_collider(&with), canal_collider(&without));
        let first = without.surface.triangles.len();
        assert_eq!(with.surface.triangles.len(), first + walls.abdominal_wall.triangles.len() + walls.obturator_membranes.triangles.len());
        for (sheet, site, offset) in [
            (&walls.abdominal_wall, ContactSite::AbdominalWall, first),
            (&walls.obturator_membranes, ContactSite::ObturatorMembrane, first + walls.abdominal_wall.triangles.len()),
        ] {
            assert!(!sheet.triangles.is_empty(), "{site:?}");
            for t in 0..sheet.triangles.len() {
                let [a, b, c] = sheet.corners(t);
                let centre = (a + b + c) / 3.0;
                // In front of the canal axis (the abdominal wall from the
                // brim up, the membranes below it), facing back into the canal.
                assert!(centre.y > 0.0, "{site:?} {t}: {centre}");
                assert!(if site == ContactSite::AbdominalWall { centre.z > -0.005 } else { centre.z < 0.0 }, "{site:?} {t}: {centre}");
                assert_eq!(with.sites[with.labels[offset + t] as usize], site);
            }
            let [a, b, c] = sheet.corners(sheet.triangles.len() / 2);
            let into_canal = (b - a).cross(c - a).normalize();
            assert!(into_canal.dot(DVec3::new(0.0, -1.0, 0.0)) > 0.0, "{site:?} faces {into_canal}");
            let behind = (a + b + c) / 3.0 - 0.002 * into_canal;
            let hit = closed.closest_point(behind, 0.01).unwrap();
            assert!((hit.signed_distance + 0.002).abs() < 1e-4 && hit.triangle as usize >= first, "{site:?}: {hit:?}");
            assert!(open.closest_point(behind, 0.001).is_none_or(|h| h.signed_distance > 0.0), "{site:?}: bone there");
        }
        // Left and right alike: the membranes are the mirror of each other.
        let x_sum: f64 = walls.obturator_membranes.vertices.iter().map(|v| v.x).sum();
        assert!(x_sum.abs() < 1e-9 * walls.obturator_membranes.vertices.len() as f64, "{x_sum}");
        // By default the abdominal wall alone (the membranes narrow the
        // turn, docs/LABOUR.md); off, the canal is the bone and the ligaments.
        assert_eq!(scene.soft_walls().unwrap(), walls.abdominal_wall);
        let mut off = scene.scenario.clone();
        off.contact.abdominal_wall = false;
        let bare = Scene::build(&off).unwrap();
        assert_eq!(bare.sites, without.sites);
        assert!(bare.soft_walls().is_none());
    }

    #[test]
    fn a_solid_box_has_the_textbook_mass_properties() {
        // Unit cube [0,1]^3 as 12 outward triangles.
        let v: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let t = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        let s = TriSurface::new(v, t);
        let (m, c, i) = solid_properties(&s, 2.0);
        assert!((m - 2.0).abs() < 1e-12);
        assert!((c - DVec3::splat(0.5)).length() < 1e-12);
        let expected = 2.0 * (1.0 + 1.0) / 12.0;
        for k in 0..3 {
            assert!((i.col(k)[k] - expected).abs() < 1e-12, "{i:?}");
            assert!(i.col(k)[(k + 1) % 3].abs() < 1e-12);
        }
    }
}
