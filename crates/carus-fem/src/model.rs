//! The immutable TLED model: everything that does not change during a run,
//! computed once from the mesh and materials (Miller et al. 2007, sec. 2):
//! reference shape-function derivatives, volumes, lumped masses, hourglass
//! vectors, the node-to-element-slot gather table and the critical time step.

use serde::{Deserialize, Serialize};

use crate::error::FemError;
use crate::kernel::blocks::{ElementBlocks, ElementInput, KernelData, NodeTable};
pub(crate) use crate::kernel::element::det3;
use crate::kernel::lanes::Real;
use crate::kernel::stability::max_angular_frequency;
use crate::material::{Material, MaterialLaw};
use crate::mesh::{ElementKind, Mesh, H8_FACES, T4_FACES};

/// Tetrahedron formulation (ignored for H8 meshes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TetFormulation {
    /// Linear tetrahedron, one integration point.
    #[default]
    T4,
    /// Average nodal pressure tetrahedron (Joldes, Wittek & Miller 2009,
    /// "Improved linear tetrahedral element for surgical simulation",
    /// Med. Eng. Phys. 31:1008): the dilatation is averaged per node over
    /// the elements sharing it, weighted by volume, and each element takes the
    /// pressure of the mean of its nodal values. Avoids volumetric locking of
    /// nearly incompressible tissue.
    T4Anp,
}

/// Precision of the step-loop kernels. The public API stays f64.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    #[default]
    F64,
    /// Single precision: twice the lanes per instruction and half the memory
    /// traffic; VALIDATION.md V2 allows 1e-4 relative error in f32.
    F32,
}

/// Options of the model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelOptions {
    pub tet_formulation: TetFormulation,
    /// NiftySim's HGKappa; 0 switches hourglass control off. Default 0.075
    /// as in VALIDATION.md V3.
    pub hourglass_coefficient: f64,
    /// The modulus that scales the hourglass stiffness.
    pub hourglass_modulus: HourglassModulus,
    /// Mass-proportional damping alpha, 1/s.
    pub damping_per_s: f64,
    pub precision: Precision,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            tet_formulation: TetFormulation::T4,
            hourglass_coefficient: 0.075,
            hourglass_modulus: HourglassModulus::Shear,
            damping_per_s: 0.0,
            precision: Precision::F64,
        }
    }
}

/// The modulus M in the H8 hourglass stiffness
/// k = HGKappa V M sum((dh/dX)^2) / 8.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HourglassModulus {
    /// M = lambda + 2 mu, the dilatational (P-wave) modulus: Flanagan &
    /// Belytschko 1981 as NiftySim implements it (DESIGN.md). Use it to
    /// compare with NiftySim; V3 does. In nearly incompressible tissue it
    /// penalises the zero-mean dilatation of the hourglass modes with the
    /// bulk modulus, which stiffens bending the way volumetric locking does:
    /// on V3 (nu = 0.49) its hourglass energy is 4.4 % of the strain energy
    /// (docs/VALIDATION.md).
    Dilatational,
    /// M = 2 mu: the stabilisation of nearly incompressible solids by the
    /// shear stiffness only (Belytschko & Bindeman 1993, Comput. Methods
    /// Appl. Mech. Engrg. 105:225-260; Puso 2000, Int. J. Numer. Meth. Engng
    /// 49:1029-1064). The default: on V3 it keeps the hourglass energy under
    /// 0.5 % and lands closer to the refined solution (docs/VALIDATION.md).
    Shear,
}

impl HourglassModulus {
    /// M in Pa for the given Lame parameters.
    pub fn value(self, lambda: f64, mu: f64) -> f64 {
        match self {
            HourglassModulus::Dilatational => lambda + 2.0 * mu,
            HourglassModulus::Shear => 2.0 * mu,
        }
    }

    /// Name as in job files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            HourglassModulus::Dilatational => "dilatational",
            HourglassModulus::Shear => "shear",
        }
    }
}

/// A material applied to an element set (None: every element). Later
/// regions override earlier ones where they overlap.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaterialRegion {
    pub element_set: Option<String>,
    pub material: Material,
    pub density_kg_m3: f64,
}

/// The kernel data in the chosen precision.
#[derive(Debug, Clone)]
pub enum KernelModel {
    F32(KernelData<f32>),
    F64(KernelData<f64>),
}

/// The constant part of a TLED simulation.
#[derive(Debug, Clone)]
pub struct TledModel {
    mesh: Mesh,
    options: ModelOptions,
    critical_time_step_s: f64,
    element_time_step_s: f64,
    critical_element: usize,
    /// Each element's reference volume (m^3) and dilatational wave speed
    /// (m/s), for the critical step of a deformed shape.
    element_scales: Vec<ElementScale>,
    /// Diagonal of the mesh's bounding box, m (scale of the runaway check).
    size_m: f64,
    kernel: KernelModel,
}

/// What the critical step of one element is made of, besides its shape.
#[derive(Debug, Clone, Copy)]
struct ElementScale {
    volume_m3: f64,
    wave_speed_m_s: f64,
}

/// Fraction of the linearised stability limit 2 / omega_max taken as the
/// critical step. Finite strain stiffens the tissue (measured: a 5 %
/// volumetric pre-strain of the V3 block lowers the limit by 4 %, 10 % by
/// 8 %), and the power iteration converges from below (0.1 %); 0.9 is also
/// LS-DYNA's default time-step scale factor (LS-DYNA Theory Manual, sec. 22).
pub const STABILITY_MARGIN: f64 = 0.9;

/// Natural-coordinate signs of the H8 nodes (VTK order).
pub(crate) const H8_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The four hourglass base vectors of the H8 (NiftySim's Gamma, node-major).
const H8_GAMMA: [[f64; 4]; 8] = [
    [1.0, 1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0, -1.0],
    [-1.0, -1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0, 1.0],
    [-1.0, -1.0, 1.0, -1.0],
    [1.0, 1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0, -1.0],
];

// Small vector helpers on the mesh's [f64; 3] coordinates, shared by the
// mesh generator and the quality checks.
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    norm_squared(a).sqrt()
}
fn norm_squared(a: [f64; 3]) -> f64 {
    a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
}
fn inverse3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let d = det3(m);
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (i1, i2) = ((j + 1) % 3, (j + 2) % 3);
            let (j1, j2) = ((i + 1) % 3, (i + 2) % 3);
            r[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / d;
        }
    }
    r
}

/// dN_a/dxi_i of the trilinear H8 shape function of the corner at natural
/// coordinates `corner` (one of [`H8_CORNERS`]), at natural point `xi`.
fn h8_natural_derivatives(corner: [f64; 3], xi: [f64; 3]) -> [f64; 3] {
    let f = [1.0 + corner[0] * xi[0], 1.0 + corner[1] * xi[1], 1.0 + corner[2] * xi[2]];
    [corner[0] * f[1] * f[2] / 8.0, corner[1] * f[0] * f[2] / 8.0, corner[2] * f[0] * f[1] / 8.0]
}

/// Jacobian dx_j/dxi_i of the trilinear H8 map at natural point `xi`.
pub(crate) fn h8_jacobian(x: &[[f64; 3]; 8], xi: [f64; 3]) -> [[f64; 3]; 3] {
    let mut jac = [[0.0; 3]; 3];
    for (a, s) in H8_CORNERS.iter().enumerate() {
        let dn = h8_natural_derivatives(*s, xi);
        for i in 0..3 {
            for j in 0..3 {
                jac[i][j] += dn[i] * x[a][j];
            }
        }
    }
    jac
}

/// Geometry of one element in the reference configuration.
pub(crate) struct ElementGeometry {
    pub shape_derivatives: [[f64; 3]; 8],
    /// Integration weight of the one-point rule (the volume).
    pub weight: f64,
    /// Exact volume, m^3.
    pub volume: f64,
    /// Characteristic length for the critical time step, m.
    pub characteristic_length: f64,
}

/// H8 geometry; errors on inverted or degenerate elements.
pub(crate) fn h8_geometry(e: usize, x: &[[f64; 3]; 8]) -> Result<ElementGeometry, FemError> {
    let g = 1.0 / 3f64.sqrt();
    let mut volume = 0.0;
    for s in H8_CORNERS {
        volume += det3(&h8_jacobian(x, [s[0] * g, s[1] * g, s[2] * g]));
    }
    let max_edge = (0..8)
        .flat_map(|a| (0..8).map(move |b| (a, b)))
        .map(|(a, b)| norm(sub(x[a], x[b])))
        .fold(0.0, f64::max);
    if volume.abs() <= 1e-9 * max_edge.powi(3) {
        return Err(FemError::DegenerateElement {
            element: e,
            volume_m3: volume,
        });
    }
    let min_corner = H8_CORNERS
        .iter()
        .map(|&s| det3(&h8_jacobian(x, s)))
        .fold(f64::INFINITY, f64::min);
    if volume < 0.0 || min_corner <= 0.0 {
        return Err(FemError::InvertedElement {
            element: e,
            jacobian: min_corner.min(volume),
        });
    }
    // Uniform-gradient (mean) shape derivatives dh = (1/V) integral of dN/dx dV
    // (Flanagan & Belytschko 1981; NiftySim's "B-matrix method"): equal to
    // NiftySim's centre-point derivatives and 8 detJ = V on parallelepipeds
    // (the V3 cube), and, unlike them, exact for affine fields on distorted
    // hexahedra (patch test V2). 2x2x2 Gauss is exact for this integrand.
    let mut dh = [[0.0; 3]; 8];
    for p in H8_CORNERS {
        let xi = [p[0] * g, p[1] * g, p[2] * g];
        let jac = h8_jacobian(x, xi);
        let det = det3(&jac);
        let inv = inverse3(&jac);
        for (a, s) in H8_CORNERS.iter().enumerate() {
            let dn = h8_natural_derivatives(*s, xi);
            for j in 0..3 {
                dh[a][j] += det * (0..3).map(|i| dn[i] * inv[j][i]).sum::<f64>() / volume;
            }
        }
    }
    Ok(ElementGeometry {
        shape_derivatives: dh,
        weight: volume,
        volume,
        characteristic_length: characteristic_length(ElementKind::H8, x, volume),
    })
}

/// The length L_e of the critical step L_e / c_e for an element of this
/// volume on these corners (Hallquist, LS-DYNA Theory Manual (2006), sec.
/// 22.1): V / A_max for H8, the minimum altitude 3 V / A_max for T4.
fn characteristic_length(kind: ElementKind, x: &[[f64; 3]], volume: f64) -> f64 {
    // One square root for the largest face: the labour run calls this on
    // every element at every rigid step.
    match kind {
        ElementKind::H8 => {
            let max_face = H8_FACES
                .iter()
                .map(|f| norm_squared(cross(sub(x[f[2]], x[f[0]]), sub(x[f[3]], x[f[1]]))))
                .fold(0.0, f64::max);
            volume / (0.5 * max_face.sqrt())
        }
        ElementKind::T4 => {
            let max_face = T4_FACES
                .iter()
                .map(|f| norm_squared(cross(sub(x[f[1]], x[f[0]]), sub(x[f[2]], x[f[0]]))))
                .fold(0.0, f64::max);
            3.0 * volume / (0.5 * max_face.sqrt())
        }
    }
}

/// T4 geometry; errors on inverted or degenerate elements.
pub(crate) fn t4_geometry(e: usize, x: &[[f64; 3]; 4]) -> Result<ElementGeometry, FemError> {
    let d = [sub(x[1], x[0]), sub(x[2], x[0]), sub(x[3], x[0])];
    let volume = det3(&d) / 6.0;
    let max_edge = (0..4)
        .flat_map(|a| (0..4).map(move |b| (a, b)))
        .map(|(a, b)| norm(sub(x[a], x[b])))
        .fold(0.0, f64::max);
    if volume.abs() <= 1e-9 * max_edge.powi(3) {
        return Err(FemError::DegenerateElement {
            element: e,
            volume_m3: volume,
        });
    }
    if volume < 0.0 {
        return Err(FemError::InvertedElement {
            element: e,
            jacobian: 6.0 * volume,
        });
    }
    let inv = inverse3(&d);
    const DN: [[f64; 3]; 4] = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let mut dh = [[0.0; 3]; 8];
    for a in 0..4 {
        for j in 0..3 {
            dh[a][j] = (0..3).map(|i| DN[a][i] * inv[j][i]).sum();
        }
    }
    Ok(ElementGeometry {
        shape_derivatives: dh,
        weight: volume,
        volume,
        characteristic_length: characteristic_length(ElementKind::T4, x, volume),
    })
}

/// H8 hourglass vectors scaled by sqrt(k): s_g,a = sqrt(k) gamma_a,g with
/// gamma = Gamma - (dh/dx)(x^T Gamma), k = HGKappa V M sum((dh/dx)^2) / 8
/// (Flanagan & Belytschko 1981 as in NiftySim, DESIGN.md, with M chosen by
/// [`HourglassModulus`]).
pub(crate) fn h8_hourglass(
    x: &[[f64; 3]; 8],
    g: &ElementGeometry,
    kappa_hg: f64,
    modulus_pa: f64,
) -> [[f64; 8]; 4] {
    let dh = &g.shape_derivatives;
    let sum_sq: f64 = dh.iter().flatten().map(|v| v * v).sum();
    let k = kappa_hg * g.volume * modulus_pa * sum_sq / 8.0;
    let sk = k.max(0.0).sqrt();
    let mut out = [[0.0; 8]; 4];
    for m in 0..4 {
        let xg: [f64; 3] = std::array::from_fn(|j| (0..8).map(|b| x[b][j] * H8_GAMMA[b][m]).sum());
        for a in 0..8 {
            let gamma = H8_GAMMA[a][m] - (0..3).map(|j| dh[a][j] * xg[j]).sum::<f64>();
            out[m][a] = sk * gamma;
        }
    }
    out
}

impl TledModel {
    /// Precomputes the model. Fails on inverted or degenerate elements (by
    /// index), on elements without a material, and on invalid options.
    pub fn new(
        mesh: &Mesh,
        materials: &[MaterialRegion],
        options: &ModelOptions,
    ) -> Result<TledModel, FemError> {
        let npe = mesh.kind.nodes_per_element();
        if !mesh.connectivity.len().is_multiple_of(npe) {
            return Err(FemError::RaggedConnectivity {
                len: mesh.connectivity.len(),
                per_element: npe,
            });
        }
        let ne = mesh.element_count();
        if ne == 0 {
            return Err(FemError::EmptyMesh);
        }
        if !(options.hourglass_coefficient.is_finite() && options.hourglass_coefficient >= 0.0) {
            return Err(FemError::InvalidOption {
                option: "hourglass_coefficient",
                reason: format!("must be >= 0, got {}", options.hourglass_coefficient),
            });
        }
        if !(options.damping_per_s.is_finite() && options.damping_per_s >= 0.0) {
            return Err(FemError::InvalidOption {
                option: "damping_per_s",
                reason: format!("must be >= 0, got {}", options.damping_per_s),
            });
        }
        if let Some(n) = mesh
            .nodes
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(FemError::NonFiniteNode { node: n });
        }
        for (e, el) in mesh.elements().enumerate() {
            if let Some(&node) = el.iter().find(|&&n| n as usize >= mesh.node_count()) {
                return Err(FemError::NodeOutOfRange {
                    element: e,
                    node,
                    node_count: mesh.node_count(),
                });
            }
        }
        // Force-copy slots are u32 offsets (about 24 per H8 element).
        if ne.div_ceil(crate::kernel::lanes::LANES) * crate::kernel::lanes::LANES * npe * 3
            > u32::MAX as usize
        {
            return Err(FemError::InvalidOption {
                option: "mesh",
                reason: format!("{ne} elements exceed the 32-bit force-slot table; split the mesh"),
            });
        }
        let region_of = assign_regions(mesh, materials)?;
        let (kernel, StepLimits { element_time_step_s, critical_element, min_length_m }, element_scales) = match options.precision
        {
            Precision::F64 => {
                let (k, limits, scales) = build_kernel::<f64>(mesh, materials, &region_of, options)?;
                (KernelModel::F64(k), limits, scales)
            }
            Precision::F32 => {
                let (k, limits, scales) = build_kernel::<f32>(mesh, materials, &region_of, options)?;
                (KernelModel::F32(k), limits, scales)
            }
        };
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &mesh.nodes {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        // Probe displacements of 1e-3 of the smallest element size.
        let probe_m = 1e-3 * min_length_m;
        let omega_max = match &kernel {
            KernelModel::F32(k) => max_angular_frequency(k, probe_m),
            KernelModel::F64(k) => max_angular_frequency(k, probe_m),
        };
        let spectral = if omega_max > 0.0 {
            STABILITY_MARGIN * 2.0 / omega_max
        } else {
            f64::INFINITY
        };
        Ok(TledModel {
            mesh: mesh.clone(),
            options: *options,
            critical_time_step_s: spectral.min(element_time_step_s),
            element_time_step_s,
            critical_element,
            element_scales,
            size_m: norm(sub(hi, lo)),
            kernel,
        })
    }

    /// Critical time step of central differences, s: the smaller of
    /// 0.9 x 2 / omega_max (largest eigenfrequency of the model linearised at
    /// the reference configuration, by power iteration, see `kernel::stability`)
    /// and the element estimate [`Self::element_time_step`].
    pub fn critical_time_step(&self) -> f64 {
        self.critical_time_step_s
    }

    /// The classical element estimate min_e L_e / c_e, s, with c_e =
    /// sqrt((lambda + 2 mu) / rho) the dilatational wave speed (Miller et al.
    /// 2007) and L_e from the LS-DYNA Theory Manual sec. 22.1 (V / A_max for
    /// H8, minimum altitude 3 V / A_max for T4). On regular meshes it lies
    /// 10-15 % above the true limit, hence the spectral check.
    pub fn element_time_step(&self) -> f64 {
        self.element_time_step_s
    }

    /// The critical step of a deformed shape, s: the element estimate
    /// min_e L_e / c_e on the elements as they are now (volume J V_e,
    /// largest face as deformed), times the margin the spectral check
    /// found at the reference ([`Self::critical_time_step`] over
    /// [`Self::element_time_step`]); at the reference it is the critical
    /// step. An element pressed flat by contact, its faces stretched at
    /// constant volume, lowers it several times, and a step the reference
    /// allowed then diverges (docs/SOLVE.md). `positions` are the nodes'
    /// current coordinates, `volume_ratios` the elements' J
    /// ([`crate::TledSolver::volume_ratios`]). An element with no length
    /// left (flat, inverted or not finite) gives 0: no step is stable.
    pub fn critical_time_step_at(&self, positions: &[[f64; 3]], volume_ratios: &[f64]) -> f64 {
        assert_eq!(positions.len(), self.mesh.node_count(), "one position per node");
        assert_eq!(volume_ratios.len(), self.mesh.element_count(), "one volume ratio per element");
        let margin = self.critical_time_step_s / self.element_time_step_s;
        let kind = self.mesh.kind;
        let mut corners = [[0.0; 3]; 8];
        let mut step = f64::INFINITY;
        for ((el, scale), &j) in self.mesh.elements().zip(&self.element_scales).zip(volume_ratios) {
            for (c, &n) in corners.iter_mut().zip(el) {
                *c = positions[n as usize];
            }
            let length = characteristic_length(kind, &corners[..el.len()], j * scale.volume_m3);
            if !length.is_finite() || length <= 0.0 {
                return 0.0;
            }
            step = step.min(length / scale.wave_speed_m_s);
        }
        margin * step
    }

    /// The element with the smallest L_e / c_e.
    pub fn critical_element(&self) -> usize {
        self.critical_element
    }

    pub fn node_count(&self) -> usize {
        self.mesh.node_count()
    }

    pub fn element_count(&self) -> usize {
        self.mesh.element_count()
    }

    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    pub fn options(&self) -> &ModelOptions {
        &self.options
    }

    /// Diagonal of the reference bounding box, m.
    pub fn size_m(&self) -> f64 {
        self.size_m
    }

    /// The kernel arrays (for other backends and benches).
    pub fn kernel(&self) -> &KernelModel {
        &self.kernel
    }

    /// Whether T4ANP is active (a T4 mesh with that formulation).
    pub fn uses_anp(&self) -> bool {
        self.mesh.kind == ElementKind::T4 && self.options.tet_formulation == TetFormulation::T4Anp
    }

    /// Lumped mass of every node, kg.
    pub fn node_masses_kg(&self) -> Vec<f64> {
        match &self.kernel {
            KernelModel::F32(k) => k.nodes.mass.iter().map(|m| m.to_f64()).collect(),
            KernelModel::F64(k) => k.nodes.mass.clone(),
        }
    }

    /// Bytes held by the model (mesh copy plus kernel arrays).
    pub fn memory_bytes(&self) -> usize {
        let mesh = self.mesh.nodes.len() * 24 + self.mesh.connectivity.len() * 4;
        mesh + match &self.kernel {
            KernelModel::F32(k) => k.bytes(),
            KernelModel::F64(k) => k.bytes(),
        }
    }
}

/// Region index of every element (later regions win).
fn assign_regions(mesh: &Mesh, materials: &[MaterialRegion]) -> Result<Vec<u16>, FemError> {
    const NONE: u16 = u16::MAX;
    let ne = mesh.element_count();
    let mut region_of = vec![NONE; ne];
    for (r, region) in materials.iter().enumerate() {
        region.material.validate()?;
        if !(region.density_kg_m3.is_finite() && region.density_kg_m3 > 0.0) {
            return Err(FemError::InvalidMaterial {
                reason: format!(
                    "density must be positive, got {} kg/m^3",
                    region.density_kg_m3
                ),
            });
        }
        let r = u16::try_from(r).map_err(|_| FemError::InvalidMaterial {
            reason: "more than 65535 material regions".into(),
        })?;
        match &region.element_set {
            None => region_of.fill(r),
            Some(name) => {
                let set = mesh
                    .element_sets
                    .get(name)
                    .ok_or_else(|| FemError::UnknownElementSet { set: name.clone() })?;
                for &e in set {
                    let slot = region_of.get_mut(e as usize).ok_or_else(|| {
                        FemError::ElementSetOutOfRange {
                            set: name.clone(),
                            element: e,
                            element_count: ne,
                        }
                    })?;
                    *slot = r;
                }
            }
        }
    }
    if let Some(e) = region_of.iter().position(|&r| r == NONE) {
        return Err(FemError::MissingMaterial { element: e });
    }
    Ok(region_of)
}

/// What the elements say of the critical step.
struct StepLimits {
    /// The element estimate min_e L_e / c_e, s.
    element_time_step_s: f64,
    /// The element that sets it.
    critical_element: usize,
    /// The smallest characteristic length L_e, m.
    min_length_m: f64,
}

fn build_kernel<T: Real>(
    mesh: &Mesh,
    materials: &[MaterialRegion],
    region_of: &[u16],
    options: &ModelOptions,
) -> Result<(KernelData<T>, StepLimits, Vec<ElementScale>), FemError> {
    let npe = mesh.kind.nodes_per_element();
    let ne = mesh.element_count();
    let nn = mesh.node_count();
    let hourglass = mesh.kind == ElementKind::H8 && options.hourglass_coefficient > 0.0;
    let anp = mesh.kind == ElementKind::T4 && options.tet_formulation == TetFormulation::T4Anp;
    let mut blocks = ElementBlocks::<T>::new(npe, ne, hourglass, anp);
    let mut mass = vec![0.0f64; nn];
    let mut nodal_volume = if anp { vec![0.0f64; nn] } else { Vec::new() };
    let mut dt_crit = f64::INFINITY;
    let mut critical_element = 0;
    let mut min_length = f64::INFINITY;
    let mut scales = Vec::with_capacity(ne);
    for (e, el) in mesh.elements().enumerate() {
        let region = &materials[region_of[e] as usize];
        let (lambda, mu) = region.material.lame_parameters();
        let mut hg = None;
        let geom = match mesh.kind {
            ElementKind::H8 => {
                let x: [[f64; 3]; 8] = std::array::from_fn(|a| mesh.nodes[el[a] as usize]);
                let g = h8_geometry(e, &x)?;
                if hourglass {
                    hg = Some(h8_hourglass(
                        &x,
                        &g,
                        options.hourglass_coefficient,
                        options.hourglass_modulus.value(lambda, mu),
                    ));
                }
                g
            }
            ElementKind::T4 => {
                let x: [[f64; 3]; 4] = std::array::from_fn(|a| mesh.nodes[el[a] as usize]);
                t4_geometry(e, &x)?
            }
        };
        let c = region
            .material
            .dilatational_wave_speed(region.density_kg_m3);
        let dt = geom.characteristic_length / c;
        scales.push(ElementScale {
            volume_m3: geom.volume,
            wave_speed_m_s: c,
        });
        min_length = min_length.min(geom.characteristic_length);
        if dt < dt_crit {
            dt_crit = dt;
            critical_element = e;
        }
        let m = region.density_kg_m3 * geom.volume / npe as f64;
        for &n in el {
            mass[n as usize] += m;
            if anp {
                nodal_volume[n as usize] += geom.volume / 4.0;
            }
        }
        blocks.set(
            e,
            &ElementInput {
                nodes: el,
                shape_derivatives: &geom.shape_derivatives[..npe],
                weight: geom.weight,
                coefficients: region.material.kernel_coefficients(),
                hourglass: hg.as_ref(),
                volume: geom.volume,
            },
        );
    }
    // Node-to-slot table in increasing element order (deterministic gather).
    let mut slot_start = vec![0u32; nn + 1];
    for &n in &mesh.connectivity {
        slot_start[n as usize + 1] += 1;
    }
    for i in 0..nn {
        slot_start[i + 1] += slot_start[i];
    }
    let mut fill: Vec<u32> = slot_start[..nn].to_vec();
    let mut slots = vec![0u32; mesh.connectivity.len()];
    for (e, el) in mesh.elements().enumerate() {
        for (a, &n) in el.iter().enumerate() {
            let f = &mut fill[n as usize];
            slots[*f as usize] = blocks.force_slot(e, a) as u32;
            *f += 1;
        }
    }
    let nodes = NodeTable {
        inv_mass: mass
            .iter()
            .map(|&m| T::from_f64(if m > 0.0 { 1.0 / m } else { 0.0 }))
            .collect(),
        mass: mass.iter().map(|&m| T::from_f64(m)).collect(),
        slot_start,
        slots,
        inv_nodal_volume: nodal_volume
            .iter()
            .map(|&v| T::from_f64(if v > 0.0 { 1.0 / v } else { 0.0 }))
            .collect(),
    };
    Ok((
        KernelData {
            elements: blocks,
            nodes,
        },
        StepLimits { element_time_step_s: dt_crit, critical_element, min_length_m: min_length },
        scales,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::box_h8;
    use proptest::prelude::*;

    fn region() -> MaterialRegion {
        MaterialRegion {
            element_set: None,
            material: Material::neo_hookean(1000.0, 50_000.0),
            density_kg_m3: 1000.0,
        }
    }

    fn unit_hex() -> [[f64; 3]; 8] {
        std::array::from_fn(|a| H8_CORNERS[a].map(|s| (s + 1.0) / 2.0))
    }

    proptest! {
        /// Hourglass vectors are orthogonal to constant and linear fields on
        /// any (distorted) hexahedron, so they never resist rigid motion or
        /// homogeneous strain.
        #[test]
        fn hourglass_vectors_are_orthogonal_to_linear_fields(d in proptest::array::uniform24(-0.15f64..0.15)) {
            let mut x = unit_hex();
            for a in 0..8 {
                for i in 0..3 {
                    x[a][i] += d[a * 3 + i];
                }
            }
            let g = h8_geometry(0, &x).unwrap();
            let hg = h8_hourglass(&x, &g, 0.1, 4.2e4);
            for v in &hg {
                prop_assert!(v.iter().sum::<f64>().abs() < 1e-12);
                for j in 0..3 {
                    prop_assert!((0..8).map(|a| v[a] * x[a][j]).sum::<f64>().abs() < 1e-12);
                }
            }
            // The uniform gradient reproduces linear fields exactly.
            for j in 0..3 {
                for k in 0..3 {
                    let grad: f64 = (0..8).map(|a| x[a][j] * g.shape_derivatives[a][k]).sum();
                    let identity = if j == k { 1.0 } else { 0.0 };
                    prop_assert!((grad - identity).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn volumes_and_masses_of_a_box() {
        let mesh = box_h8([0.2, 0.1, 0.05], [4, 2, 1]);
        let m = TledModel::new(&mesh, &[region()], &ModelOptions::default()).unwrap();
        let total: f64 = m.node_masses_kg().iter().sum();
        assert!((total - 1000.0 * 0.2 * 0.1 * 0.05).abs() < 1e-12);
        assert!(m.critical_time_step() > 0.0 && m.critical_time_step() <= m.element_time_step());
    }

    #[test]
    fn inverted_input_element_is_reported_by_index() {
        let mut mesh = box_h8([0.1; 3], [3, 1, 1]);
        // Swap bottom and top faces of element 2.
        let el: Vec<u32> = mesh.element(2).to_vec();
        for a in 0..4 {
            mesh.connectivity[2 * 8 + a] = el[a + 4];
            mesh.connectivity[2 * 8 + a + 4] = el[a];
        }
        match TledModel::new(&mesh, &[region()], &ModelOptions::default()) {
            Err(FemError::InvertedElement { element, .. }) => assert_eq!(element, 2),
            other => panic!("expected an inverted element, got {other:?}"),
        }
    }

    #[test]
    fn degenerate_and_unmaterialled_elements_are_reported() {
        let mut mesh = box_h8([0.1; 3], [2, 1, 1]);
        let flat: Vec<u32> = mesh.element(1)[..4].to_vec();
        for a in 0..4 {
            mesh.connectivity[8 + 4 + a] = flat[a];
        }
        assert!(matches!(
            TledModel::new(&mesh, &[region()], &ModelOptions::default()),
            Err(FemError::DegenerateElement { element: 1, .. })
        ));

        let mut mesh = box_h8([0.1; 3], [2, 1, 1]);
        mesh.element_sets.insert("left".into(), vec![0]);
        let only_left = MaterialRegion {
            element_set: Some("left".into()),
            ..region()
        };
        assert!(matches!(
            TledModel::new(&mesh, &[only_left], &ModelOptions::default()),
            Err(FemError::MissingMaterial { element: 1 })
        ));
        let unknown = MaterialRegion {
            element_set: Some("nope".into()),
            ..region()
        };
        assert!(matches!(
            TledModel::new(&mesh, &[region(), unknown], &ModelOptions::default()),
            Err(FemError::UnknownElementSet { .. })
        ));
    }

    #[test]
    fn later_regions_override_earlier_ones() {
        let mut mesh = box_h8([0.1; 3], [2, 1, 1]);
        mesh.element_sets.insert("right".into(), vec![1]);
        let stiff = MaterialRegion {
            element_set: Some("right".into()),
            material: Material::neo_hookean(4000.0, 90_000.0),
            density_kg_m3: 1000.0,
        };
        let m = TledModel::new(&mesh, &[region(), stiff], &ModelOptions::default()).unwrap();
        let KernelModel::F64(k) = m.kernel() else {
            panic!("f64 model")
        };
        assert_eq!(k.elements.coefficient(0, 0), 500.0);
        assert_eq!(k.elements.coefficient(1, 0), 2000.0);
        assert_eq!(k.elements.coefficient(1, 2), 90_000.0);
    }
}
