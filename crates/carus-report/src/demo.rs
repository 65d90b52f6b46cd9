//! A report from a synthetic history, for the tests, the sample in
//! docs/examples and anyone who wants to see a report without a run: the
//! textbook trajectory of carus-analysis (imposed, not simulated) through
//! the default generated pelvis, with the average term fetus and the
//! default pelvic floor drawn at rest.

use carus_analysis::synthetic::{straight_push, textbook_plan};
use carus_analysis::{
    detect, BirthCanal, DetectorReport, HeadGeometry, PoseHistory, TrunkGeometry,
};
use carus_anatomy::fetus::Fetus;
use carus_anatomy::floor::{pelvic_floor, FloorParameters, LOWER_SURFACE, UPPER_SURFACE};
use carus_anatomy::pelvis::PelvisDiameters;
use carus_anatomy::Pelvis;
use glam::DVec3;

use crate::error::ReportError;
use crate::input::{FloorSurface, Fontanelles, ReportInput, ReportScene, RunFigures};

/// What the page says first about a synthetic report made by `function`
/// of carus-analysis's `synthetic` module.
pub fn synthetic_notice(function: &str) -> String {
    format!(
        "Synthetic demonstration: the fetus follows an imposed trajectory \
         (carus-analysis synthetic::{function}), not the physics. The detector judged it like \
         any run. No pelvic floor was simulated: the floor is drawn at rest."
    )
}

/// The anatomy, history and detector report of a demonstration.
pub struct Demo {
    pub pelvis: Pelvis,
    pub fetus: Fetus,
    pub floor: FloorSurface,
    pub history: PoseHistory,
    pub detector: DetectorReport,
    /// The synthetic history's name in carus-analysis ("textbook").
    pub source: &'static str,
}

impl Demo {
    /// The textbook normal labour through the default pelvis.
    pub fn textbook() -> Result<Self, ReportError> {
        Self::build("textbook", |canal, head, trunk| {
            textbook_plan(canal).history_with(canal, head, trunk)
        })
    }

    /// The straight push (no rotation, no trunk) through the default pelvis.
    pub fn straight_push() -> Result<Self, ReportError> {
        Self::build("straight_push", |canal, _, _| straight_push(canal))
    }

    fn build(
        source: &'static str,
        history: impl Fn(&BirthCanal, &HeadGeometry, &TrunkGeometry) -> PoseHistory,
    ) -> Result<Self, ReportError> {
        let fail = |e: &dyn std::fmt::Display| ReportError::Demo(e.to_string());
        let pelvis = Pelvis::generate(&PelvisDiameters::default()).map_err(|e| fail(&e))?;
        let fetus = Fetus::term().map_err(|e| fail(&e))?;
        let mesh = pelvic_floor(&pelvis, &FloorParameters::default()).map_err(|e| fail(&e))?;
        let canal = BirthCanal::from_pelvis(&pelvis).map_err(|e| fail(&e))?;
        let history = history(
            &canal,
            &HeadGeometry::from_fetal_head(&fetus.head),
            &TrunkGeometry::from_trunk(&fetus.trunk),
        );
        let detector = detect(&history).map_err(|e| fail(&e))?;
        let triangles = [UPPER_SURFACE, LOWER_SURFACE]
            .iter()
            .filter_map(|name| mesh.surfaces.get(*name))
            .flatten()
            .copied()
            .collect();
        let floor = FloorSurface {
            triangles,
            rest_positions_m: mesh.nodes.iter().map(|&p| DVec3::from_array(p)).collect(),
            frames: Vec::new(),
        };
        Ok(Demo {
            pelvis,
            fetus,
            floor,
            history,
            detector,
            source,
        })
    }

    /// The report input: every part the demonstration has, no floor stretch.
    pub fn input(&self, title: &str) -> ReportInput<'_> {
        let series = &self.detector.series;
        let simulated_s = series.time_s.last().copied().unwrap_or(0.0) - series.time_s[0];
        ReportInput {
            title: title.to_string(),
            notice: Some(synthetic_notice(self.source)),
            scenario_toml: None,
            run: RunFigures {
                simulated_s,
                wall_s: None,
                steps: None,
                extra: vec![("trajectory".into(), "imposed (synthetic)".into())],
            },
            history: &self.history,
            detector: &self.detector,
            floor_peak_stretch: Vec::new(),
            floor_untrusted_from_s: None,
            head_axial_moments: Vec::new(),
            head_canal_forces: Vec::new(),
            contact_load_n: Vec::new(),
            scene: Some(ReportScene {
                pelvis: Some(self.pelvis.surface.clone()),
                head: self.fetus.head.surface.clone(),
                trunk: self
                    .history
                    .trunk
                    .as_ref()
                    .map(|_| self.fetus.trunk.surface.clone()),
                lower_trunk: None,
                floor: Some(self.floor.clone()),
                fontanelles: Some(Fontanelles {
                    anterior: self.fetus.head.landmarks.bregma,
                    posterior: self.fetus.head.landmarks.lambda,
                }),
                forces: Vec::new(),
            }),
        }
    }
}
