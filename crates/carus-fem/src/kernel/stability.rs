//! The stability limit of central differences, 2 / omega_max, from the
//! largest eigenvalue of M^-1 K of the linearised model (small-strain
//! stiffness at the reference configuration, hourglass springs included,
//! lumped masses, free boundary, which bounds every constrained case from
//! above).
//!
//! Why not only L_e / c: on regular cube meshes that estimate (V / A_max for
//! H8, minimum altitude for T4, LS-DYNA Theory Manual sec. 22.1) was measured
//! 10-15 % above the true limit of one-point H8 and of T4 with lumped masses
//! (the corner and surface nodes carry small masses), so a step that passed it
//! could still blow up. The power iteration below converges on these meshes to
//! 0.1 % in 50 iterations (Rayleigh quotients approach omega_max^2 from below).

use rayon::prelude::*;

use super::blocks::KernelData;
use super::lanes::Real;

/// Rayleigh-quotient iterations: at least, at most, and the relative change
/// that ends them.
const MIN_ITERATIONS: usize = 20;
const MAX_ITERATIONS: usize = 300;
const TOLERANCE: f64 = 1e-5;

/// y = K v (linear elasticity with lambda = kappa - 2 mu / 3, mu = 2 (c10 + c01),
/// plus the hourglass springs), written per element into `copies` and gathered per node.
fn stiffness_action<T: Real>(k: &KernelData<T>, v: &[f64], copies: &mut [f64], y: &mut [f64]) {
    let eb = &k.elements;
    let npe = eb.nodes_per_element;
    copies.par_chunks_mut(npe * 3).enumerate().for_each(|(e, out)| {
        if e >= eb.element_count {
            return;
        }
        let mut g = [[0.0f64; 3]; 3];
        for a in 0..npe {
            let n = eb.node(e, a);
            for i in 0..3 {
                for j in 0..3 {
                    g[i][j] += v[3 * n + i] * eb.shape_derivative(e, a, j);
                }
            }
        }
        let mu = 2.0 * (eb.coefficient(e, 0) + eb.coefficient(e, 1));
        let lambda = eb.coefficient(e, 2) - 2.0 * mu / 3.0;
        let tr = g[0][0] + g[1][1] + g[2][2];
        let w = eb.element_weight(e);
        let mut sigma = [[0.0f64; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                sigma[i][j] = w * (mu * (g[i][j] + g[j][i]) + if i == j { lambda * tr } else { 0.0 });
            }
        }
        for a in 0..npe {
            for i in 0..3 {
                out[a * 3 + i] = (0..3).map(|j| sigma[i][j] * eb.shape_derivative(e, a, j)).sum();
            }
        }
        if !eb.hourglass.is_empty() {
            for g in 0..4 {
                for c in 0..3 {
                    let q: f64 = (0..8).map(|b| eb.hourglass_vector(e, g, b) * v[3 * eb.node(e, b) + c]).sum();
                    for a in 0..8 {
                        out[a * 3 + c] += eb.hourglass_vector(e, g, a) * q;
                    }
                }
            }
        }
    });
    // Gather in the fixed slot order (deterministic).
    y.par_chunks_mut(3).enumerate().for_each(|(n, yn)| {
        yn.fill(0.0);
        for &s in k.nodes.slots_of(n) {
            let (e, a) = (eb.slot_element(s as usize), eb.slot_local_node(s as usize));
            for c in 0..3 {
                yn[c] += copies[e * npe * 3 + a * 3 + c];
            }
        }
    });
}

/// Largest angular frequency omega_max of the linearised model, rad/s.
pub fn max_angular_frequency<T: Real>(k: &KernelData<T>) -> f64 {
    let nn = k.nodes.mass.len();
    let inv_mass: Vec<f64> = k.nodes.inv_mass.iter().map(|m| m.to_f64()).collect();
    // Deterministic start rich in short waves: a hashed sign per dof.
    let mut v: Vec<f64> = (0..3 * nn)
        .map(|i| {
            let h = (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15).rotate_left(17);
            if h & 1 == 0 { 1.0 } else { -1.0 }
        })
        .collect();
    let mut y = vec![0.0; 3 * nn];
    let mut copies = vec![0.0; k.elements.element_count * k.elements.nodes_per_element * 3];
    let mut lambda = 0.0f64;
    for it in 0..MAX_ITERATIONS {
        // Symmetric form: z = M^-1/2 K M^-1/2 v, Rayleigh quotient v.z / v.v.
        let scaled: Vec<f64> = v.iter().enumerate().map(|(i, x)| x * inv_mass[i / 3].sqrt()).collect();
        stiffness_action(k, &scaled, &mut copies, &mut y);
        for (i, yi) in y.iter_mut().enumerate() {
            *yi *= inv_mass[i / 3].sqrt();
        }
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
        let converged = it >= MIN_ITERATIONS && (next - lambda).abs() <= TOLERANCE * next;
        lambda = next;
        if converged {
            break;
        }
    }
    lambda.max(0.0).sqrt()
}
