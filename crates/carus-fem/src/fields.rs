//! Output quantities evaluated from a displacement state, in f64: per-element
//! von Mises stress, maximum principal stretch and Jacobian, and the
//! kinetic, strain and hourglass energies. Evaluated on demand (for output
//! frames), never inside the step loop; the volume ratios alone are cheap
//! enough for a coupling loop to read every step.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::kernel::blocks::KernelData;
use crate::kernel::element::{
    add_hourglass_forces, deformation_gradient, det3, hourglass_amplitudes, right_cauchy_green,
    second_piola_kirchhoff, strain_energy_density, Coefficients, Sym,
};
use crate::kernel::lanes::Real;

/// Per-element fields, one value per element in mesh order.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ElementFields {
    /// Von Mises equivalent of the Cauchy stress, Pa.
    pub von_mises_pa: Vec<f64>,
    /// Largest principal stretch, sqrt of the largest eigenvalue of C.
    pub max_principal_stretch: Vec<f64>,
    /// J = det F.
    pub jacobian: Vec<f64>,
}

/// Energies of the current state, J.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Energies {
    /// 1/2 sum m v^2 with the backward-difference velocity of the last step.
    pub kinetic_j: f64,
    /// Integral of W over the elements (one-point rule).
    pub strain_j: f64,
    /// Energy stored in the hourglass springs, 1/2 u^T K_hg u.
    pub hourglass_j: f64,
}

/// Largest eigenvalue of a symmetric 3x3 tensor (trigonometric closed form,
/// Smith 1961).
pub fn largest_eigenvalue(c: &Sym<f64>) -> f64 {
    let p1 = c.xy * c.xy + c.yz * c.yz + c.xz * c.xz;
    let q = c.trace() / 3.0;
    if p1 <= 1e-30 * (q * q).max(1e-300) {
        return c.xx.max(c.yy).max(c.zz);
    }
    let p2 = (c.xx - q).powi(2) + (c.yy - q).powi(2) + (c.zz - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = Sym {
        xx: (c.xx - q) / p,
        yy: (c.yy - q) / p,
        zz: (c.zz - q) / p,
        xy: c.xy / p,
        yz: c.yz / p,
        xz: c.xz / p,
    };
    let r = (b.det() / 2.0).clamp(-1.0, 1.0);
    q + 2.0 * p * (r.acos() / 3.0).cos()
}

/// Von Mises equivalent of a symmetric stress.
pub fn von_mises(s: &Sym<f64>) -> f64 {
    (0.5 * ((s.xx - s.yy).powi(2) + (s.yy - s.zz).powi(2) + (s.zz - s.xx).powi(2))
        + 3.0 * (s.xy * s.xy + s.yz * s.yz + s.xz * s.xz))
        .sqrt()
}

/// Cauchy stress sigma = F S F^T / J.
fn cauchy(f: &[[f64; 3]; 3], s: &Sym<f64>, j: f64) -> Sym<f64> {
    let sr = s.to_rows();
    let mut fs = [[0.0; 3]; 3];
    for i in 0..3 {
        for k in 0..3 {
            fs[i][k] = (0..3).map(|m| f[i][m] * sr[m][k]).sum();
        }
    }
    let e = |i: usize, k: usize| (0..3).map(|m| fs[i][m] * f[k][m]).sum::<f64>() / j;
    Sym {
        xx: e(0, 0),
        yy: e(1, 1),
        zz: e(2, 2),
        xy: e(0, 1),
        yz: e(1, 2),
        xz: e(0, 2),
    }
}

struct ElementResult {
    von_mises: f64,
    stretch: f64,
    jacobian: f64,
    strain_j: f64,
    hourglass_j: f64,
}

/// One element's nodal displacements and shape derivatives, in f64.
#[inline(always)]
fn element_state<T: Real, const N: usize>(
    k: &KernelData<T>,
    e: usize,
    u: &[T],
) -> ([[f64; 3]; N], [[f64; 3]; N]) {
    let eb = &k.elements;
    let ue = std::array::from_fn(|a| std::array::from_fn(|c| u[3 * eb.node(e, a) + c].to_f64()));
    let dh = std::array::from_fn(|a| std::array::from_fn(|i| eb.shape_derivative(e, a, i)));
    (ue, dh)
}

/// Per element, J = det F alone: cheap enough for a coupling loop to read
/// every step, without the stresses, stretches and energies of [`evaluate`].
pub(crate) fn volume_ratios<T: Real>(k: &KernelData<T>, u: &[T]) -> Vec<f64> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: FMA support was detected at run time.
        return unsafe { volume_ratios_fma(k, u) };
    }
    volume_ratios_body(k, u)
}

/// [`volume_ratios`] with the processor's fused multiply-add. Without it
/// every `mul_add` of the deformation gradient is a library call, which
/// made this loop cost a tenth of a labour run. Bit for bit the same: a
/// fused multiply-add rounds once, in the library as in the processor.
#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
#[target_feature(enable = "fma")]
unsafe fn volume_ratios_fma<T: Real>(k: &KernelData<T>, u: &[T]) -> Vec<f64> {
    volume_ratios_body(k, u)
}

#[inline(always)]
fn volume_ratios_body<T: Real>(k: &KernelData<T>, u: &[T]) -> Vec<f64> {
    let count = k.elements.element_count;
    let mut ratios = Vec::with_capacity(count);
    for e in 0..count {
        ratios.push(match k.elements.nodes_per_element {
            8 => {
                let (ue, dh) = element_state::<T, 8>(k, e, u);
                det3(&deformation_gradient(&ue, &dh))
            }
            _ => {
                let (ue, dh) = element_state::<T, 4>(k, e, u);
                det3(&deformation_gradient(&ue, &dh))
            }
        });
    }
    ratios
}

fn evaluate_element<T: Real, const N: usize>(
    k: &KernelData<T>,
    e: usize,
    u: &[T],
    nodal_j: Option<&[f64]>,
) -> ElementResult {
    let eb = &k.elements;
    let (ue, dh) = element_state::<T, N>(k, e, u);
    let co = Coefficients {
        c10: eb.coefficient(e, 0),
        c01: eb.coefficient(e, 1),
        kappa: eb.coefficient(e, 2),
    };
    let w = eb.element_weight(e);
    let f = deformation_gradient(&ue, &dh);
    let j = det3(&f);
    let c = right_cauchy_green(&f);
    let j_vol = nodal_j.map_or(j, |nj| {
        (0..N).map(|a| nj[eb.node(e, a)]).sum::<f64>() / N as f64
    });
    let s = second_piola_kirchhoff(&c, j, j_vol, &co);
    // T4ANP stores its volumetric energy per node (see `anp_nodal_state`).
    let energy_co = if nodal_j.is_some() {
        Coefficients { kappa: 0.0, ..co }
    } else {
        co
    };
    let hourglass_j = if eb.hourglass.is_empty() || N != 8 {
        0.0
    } else {
        let hg: [[f64; N]; 4] =
            std::array::from_fn(|g| std::array::from_fn(|a| eb.hourglass_vector(e, g, a)));
        let q = hourglass_amplitudes(&ue, &hg);
        // E_hg = 1/2 u . K_hg u = 1/2 u . f_hg.
        let mut fhg = [[0.0; 3]; N];
        add_hourglass_forces(&mut fhg, &q, &hg);
        0.5 * (0..N)
            .map(|a| (0..3).map(|c| ue[a][c] * fhg[a][c]).sum::<f64>())
            .sum::<f64>()
    };
    ElementResult {
        von_mises: von_mises(&cauchy(&f, &s, j)),
        stretch: largest_eigenvalue(&c).max(0.0).sqrt(),
        jacobian: j,
        strain_j: w * strain_energy_density(&c, j, j_vol, &energy_co),
        hourglass_j,
    }
}

/// T4ANP in f64: the nodal dilatation J_n and the volumetric energy
/// sum_n V_n kappa_n / 2 (J_n - 1)^2, of which the ANP forces are exactly the
/// gradient for one material (kappa_n: volume-weighted mean over the node's
/// elements).
fn anp_nodal_state<T: Real>(k: &KernelData<T>, u: &[T]) -> (Vec<f64>, f64) {
    let eb = &k.elements;
    let nn = k.nodes.mass.len();
    let shares: Vec<f64> = (0..eb.element_count)
        .into_par_iter()
        .map(|e| {
            let (ue, dh) = element_state::<T, 4>(k, e, u);
            det3(&deformation_gradient(&ue, &dh)) * eb.quarter_volume[e].to_f64()
        })
        .collect();
    let per_node: Vec<(f64, f64)> = (0..nn)
        .map(|n| {
            let inv = k.nodes.inv_nodal_volume[n].to_f64();
            if inv <= 0.0 {
                return (1.0, 0.0);
            }
            let slots = k.nodes.slots_of(n);
            let j = slots
                .iter()
                .map(|&s| shares[eb.slot_element(s as usize)])
                .sum::<f64>()
                * inv;
            let kappa_v: f64 = slots
                .iter()
                .map(|&s| {
                    let e = eb.slot_element(s as usize);
                    eb.coefficient(e, 2) * eb.quarter_volume[e].to_f64()
                })
                .sum();
            (j, 0.5 * kappa_v * (j - 1.0) * (j - 1.0))
        })
        .collect();
    (
        per_node.iter().map(|p| p.0).collect(),
        per_node.iter().map(|p| p.1).sum(),
    )
}

/// Fields and element energies (strain, hourglass) of displacement `u`.
pub(crate) fn evaluate<T: Real>(
    k: &KernelData<T>,
    anp: bool,
    u: &[T],
) -> (ElementFields, f64, f64) {
    let (nodal_j, volumetric_j) = if anp {
        let (j, energy) = anp_nodal_state(k, u);
        (Some(j), energy)
    } else {
        (None, 0.0)
    };
    let nj = nodal_j.as_deref();
    let results: Vec<ElementResult> = (0..k.elements.element_count)
        .into_par_iter()
        .map(|e| match k.elements.nodes_per_element {
            8 => evaluate_element::<T, 8>(k, e, u, nj),
            _ => evaluate_element::<T, 4>(k, e, u, nj),
        })
        .collect();
    let fields = ElementFields {
        von_mises_pa: results.iter().map(|r| r.von_mises).collect(),
        max_principal_stretch: results.iter().map(|r| r.stretch).collect(),
        jacobian: results.iter().map(|r| r.jacobian).collect(),
    };
    (
        fields,
        volumetric_j + results.iter().map(|r| r.strain_j).sum::<f64>(),
        results.iter().map(|r| r.hourglass_j).sum(),
    )
}

/// Kinetic energy with velocity (u - u_prev) / h.
pub(crate) fn kinetic_energy<T: Real>(k: &KernelData<T>, u: &[T], u_prev: &[T], h: f64) -> f64 {
    k.nodes
        .mass
        .iter()
        .enumerate()
        .map(|(n, m)| {
            let v2: f64 = (0..3)
                .map(|c| ((u[3 * n + c].to_f64() - u_prev[3 * n + c].to_f64()) / h).powi(2))
                .sum();
            0.5 * m.to_f64() * v2
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalue_of_diagonal_and_rotated() {
        let d = Sym {
            xx: 2.0,
            yy: 5.0,
            zz: 3.0,
            xy: 0.0,
            yz: 0.0,
            xz: 0.0,
        };
        assert_eq!(largest_eigenvalue(&d), 5.0);
        // [[2,1,0],[1,2,0],[0,0,1]] has eigenvalues 3, 1, 1.
        let s = Sym {
            xx: 2.0,
            yy: 2.0,
            zz: 1.0,
            xy: 1.0,
            yz: 0.0,
            xz: 0.0,
        };
        assert!((largest_eigenvalue(&s) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn von_mises_of_uniaxial_and_hydrostatic() {
        let uni = Sym {
            xx: 7.0,
            yy: 0.0,
            zz: 0.0,
            xy: 0.0,
            yz: 0.0,
            xz: 0.0,
        };
        assert!((von_mises(&uni) - 7.0).abs() < 1e-12);
        let hyd = Sym {
            xx: 4.0,
            yy: 4.0,
            zz: 4.0,
            xy: 0.0,
            yz: 0.0,
            xz: 0.0,
        };
        assert!(von_mises(&hyd).abs() < 1e-12);
    }
}
