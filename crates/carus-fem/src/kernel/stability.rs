//! The stability limit of central differences, 2 / omega_max, from the
//! largest eigenvalue of M^-1 K of the model linearised at the reference
//! configuration (hourglass springs included, lumped masses, free boundary,
//! which bounds every constrained case from above).
//!
//! Why not only L_e / c: on regular cube meshes that estimate (V / A_max for
//! H8, minimum altitude for T4, LS-DYNA Theory Manual sec. 22.1) was measured
//! 10-15 % above the true limit of one-point H8 and of T4 with lumped masses
//! (the corner and surface nodes carry small masses), so a step that passed it
//! could still blow up.
//!
//! K v is evaluated with the step loop's own element pass, as a central
//! difference of the internal forces at +-d v with strains of about 1e-3, so
//! it costs two element passes per iteration and needs no second element
//! implementation. For T4ANP it is plain T4's pass (no nodal dilatation):
//! ANP averages the volumetric strain over each node's elements, so its
//! volumetric energy is no larger (Jensen's inequality) and plain T4's
//! limit is the safe side. The Rayleigh quotient converges from below; on the V3
//! cube meshes (n = 20, H8 and T4) 30 iterations come within 0.1 % of 200.

use super::blocks::KernelData;
use super::lanes::Real;
use super::passes;

/// Iterations: at least, at most, and the relative change that ends them.
const MIN_ITERATIONS: usize = 10;
const MAX_ITERATIONS: usize = 30;
const TOLERANCE: f64 = 1e-3;

/// Internal forces at displacement `u` (in the kernel precision), gathered per node.
fn forces_at<T: Real>(k: &KernelData<T>, u: &[T], copies: &mut [T], out: &mut [f64]) {
    // Far below inversion: the probe strains are about 1e-3.
    let _ = passes::element_forces(&k.elements, u, None, copies);
    for (n, o) in out.chunks_exact_mut(3).enumerate() {
        let f = k.nodes.gather(copies, n);
        for c in 0..3 {
            o[c] = f[c].to_f64();
        }
    }
}

/// Largest angular frequency omega_max of the linearised model, rad/s.
/// `probe_m`: the displacement amplitude of the probe (about 1e-3 of the
/// smallest element size).
pub fn max_angular_frequency<T: Real>(k: &KernelData<T>, probe_m: f64) -> f64 {
    let nn = k.nodes.mass.len();
    let inv_sqrt_mass: Vec<f64> = k.nodes.inv_mass.iter().map(|m| m.to_f64().sqrt()).collect();
    // Deterministic start rich in short waves: a hashed sign per dof.
    let mut v: Vec<f64> = (0..3 * nn)
        .map(|i| {
            let h = (i as u64)
                .wrapping_mul(0x9e37_79b9_7f4a_7c15)
                .rotate_left(17);
            if h & 1 == 0 {
                1.0
            } else {
                -1.0
            }
        })
        .collect();
    let mut u = vec![T::default(); 3 * nn];
    let mut copies = vec![T::default(); k.elements.force_copy_len()];
    let mut f_plus = vec![0.0; 3 * nn];
    let mut f_minus = vec![0.0; 3 * nn];
    let mut lambda = 0.0f64;
    for it in 0..MAX_ITERATIONS {
        // Symmetric form: y = M^-1/2 K M^-1/2 v, Rayleigh quotient v.y / v.v.
        let w: Vec<f64> = v
            .iter()
            .enumerate()
            .map(|(i, x)| x * inv_sqrt_mass[i / 3])
            .collect();
        let w_max = w.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if !(w_max > 0.0) {
            break;
        }
        let d = probe_m / w_max;
        for (ui, wi) in u.iter_mut().zip(&w) {
            *ui = T::from_f64(d * wi);
        }
        forces_at(k, &u, &mut copies, &mut f_plus);
        for (ui, wi) in u.iter_mut().zip(&w) {
            *ui = T::from_f64(-d * wi);
        }
        forces_at(k, &u, &mut copies, &mut f_minus);
        let y: Vec<f64> = (0..3 * nn)
            .map(|i| (f_plus[i] - f_minus[i]) / (2.0 * d) * inv_sqrt_mass[i / 3])
            .collect();
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let vy: f64 = v.iter().zip(&y).map(|(a, b)| a * b).sum();
        let next = vy / vv;
        let yn = y.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(yn > 0.0) {
            break;
        }
        for (vi, yi) in v.iter_mut().zip(&y) {
            *vi = yi / yn;
        }
        let converged = it + 1 >= MIN_ITERATIONS && (next - lambda).abs() <= TOLERANCE * next;
        lambda = next;
        if converged {
            break;
        }
    }
    lambda.max(0.0).sqrt()
}
