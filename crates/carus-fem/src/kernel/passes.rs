//! The parallel passes of one TLED step over the block layout:
//! element forces (per block, into force copies), the T4ANP dilatation
//! passes, and the node pass (gather + central-difference update).
//!
//! Each pass splits its output array into fixed chunks, so every value is
//! computed by the same instructions in the same order whatever the thread
//! count: results are bit-for-bit reproducible. The inner functions are
//! compiled twice, with and without AVX2, and chosen at run time.

use rayon::prelude::*;

use super::blocks::{ElementBlocks, NodeTable};
use super::element::{internal_forces, Coefficients};
use super::lanes::{block_view, block_view_mut, Lanes, Real, LANES};

/// Blocks per parallel task (512 elements).
pub(crate) const BLOCKS_PER_TASK: usize = 64;
/// Nodes per parallel task: small enough that the tasks of a 10^4-node
/// mesh split evenly over the threads.
pub(crate) const NODES_PER_TASK: usize = 512;

/// Whether the AVX2 versions can run on this CPU (cached by std): they
/// are built with FMA too, which a few CPUs and VMs offer AVX2 without.
#[inline]
fn has_avx2() -> bool {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        false
    }
}

/// The first element (lowest index) whose J is not positive, with that J
/// (NaN when the state is no longer finite).
pub type BadElement = Option<(usize, f64)>;

fn first_bad(a: BadElement, b: BadElement) -> BadElement {
    match (a, b) {
        (Some(x), Some(y)) => Some(if x.0 <= y.0 { x } else { y }),
        (x, None) => x,
        (None, y) => y,
    }
}

/// Displacements of the block's nodes, lane-major. Each lane value is
/// assembled in registers (one bounds check per node), not stored lane by
/// lane and re-read as a vector, which would stall store forwarding.
#[inline(always)]
fn gather_displacements<T: Real, const N: usize>(conn: &[u32], u: &[T]) -> [[Lanes<T>; 3]; N] {
    // Built node by node, so the block is never zero-filled first.
    std::array::from_fn(|a| {
        let mut x = [T::default(); LANES];
        let mut y = [T::default(); LANES];
        let mut z = [T::default(); LANES];
        for l in 0..LANES {
            let n = conn[a * LANES + l] as usize * 3;
            let p = &u[n..n + 3];
            x[l] = p[0];
            y[l] = p[1];
            z[l] = p[2];
        }
        [Lanes(x), Lanes(y), Lanes(z)]
    })
}

#[inline(always)]
fn element_task_body<T: Real, const N: usize>(
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    nodal_j: Option<&[T]>,
    out: &mut [T],
) -> BadElement {
    let stride = N * 3 * LANES;
    let mut bad = None;
    for (bi, ob) in out.chunks_exact_mut(stride).enumerate() {
        let b = first_block + bi;
        let conn = &eb.connectivity[b * N * LANES..(b + 1) * N * LANES];
        let ue = gather_displacements::<T, N>(conn, u);
        // Model data is read in place through lane-major views (no copies,
        // no closures that could escape the AVX2 context).
        let dh: &[[Lanes<T>; 3]; N] = block_view(&eb.shape_derivatives[b * N * 3 * LANES..]);
        let w = Lanes::load(&eb.weight[b * LANES..]);
        let co = &eb.coefficients[b * 3 * LANES..];
        let k = Coefficients {
            c10: Lanes::load(co),
            c01: Lanes::load(&co[LANES..]),
            kappa: Lanes::load(&co[2 * LANES..]),
        };
        let j_vol = match nodal_j {
            Some(nj) => {
                let mut s = [T::default(); LANES];
                for (l, sl) in s.iter_mut().enumerate() {
                    let mut acc = T::default();
                    for a in 0..N {
                        acc += nj[conn[a * LANES + l] as usize];
                    }
                    *sl = acc * T::from_f64(1.0 / N as f64);
                }
                Some(Lanes(s))
            }
            None => None,
        };
        let (f, j) = if eb.hourglass.is_empty() || N != 8 {
            internal_forces::<Lanes<T>, N>(&ue, dh, w, &k, j_vol, None)
        } else {
            let hg: &[[Lanes<T>; N]; 4] = block_view(&eb.hourglass[b * 4 * N * LANES..]);
            internal_forces::<Lanes<T>, N>(&ue, dh, w, &k, j_vol, Some(hg))
        };
        *block_view_mut::<T, N, 3>(ob) = f;
        if bad.is_none() {
            for l in 0..LANES {
                let jl = j.0[l];
                let positive = jl > T::default();
                if !positive {
                    bad = Some((b * LANES + l, jl.to_f64()));
                    break;
                }
            }
        }
    }
    bad
}

#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
fn element_task_avx2<T: Real, const N: usize>(
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    nodal_j: Option<&[T]>,
    out: &mut [T],
) -> BadElement {
    element_task_body::<T, N>(eb, first_block, u, nodal_j, out)
}

fn element_task_portable<T: Real, const N: usize>(
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    nodal_j: Option<&[T]>,
    out: &mut [T],
) -> BadElement {
    element_task_body::<T, N>(eb, first_block, u, nodal_j, out)
}

fn element_task<T: Real, const N: usize>(
    avx2: bool,
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    nodal_j: Option<&[T]>,
    out: &mut [T],
) -> BadElement {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    if avx2 {
        // SAFETY: AVX2 and FMA support was detected at run time.
        return unsafe { element_task_avx2::<T, N>(eb, first_block, u, nodal_j, out) };
    }
    let _ = avx2;
    element_task_portable::<T, N>(eb, first_block, u, nodal_j, out)
}

/// Element pass: writes every element's internal nodal forces (stress plus
/// hourglass) into `forces` (layout of [`ElementBlocks::force_slot`]).
/// `nodal_j`: the averaged nodal dilatation for T4ANP, None otherwise.
pub fn element_forces<T: Real>(
    eb: &ElementBlocks<T>,
    u: &[T],
    nodal_j: Option<&[T]>,
    forces: &mut [T],
) -> BadElement {
    let avx2 = has_avx2();
    let npe = eb.nodes_per_element;
    let task = BLOCKS_PER_TASK * npe * 3 * LANES;
    forces
        .par_chunks_mut(task)
        .enumerate()
        .map(|(t, out)| {
            let first_block = t * BLOCKS_PER_TASK;
            match npe {
                8 => element_task::<T, 8>(avx2, eb, first_block, u, nodal_j, out),
                _ => element_task::<T, 4>(avx2, eb, first_block, u, nodal_j, out),
            }
        })
        .reduce(|| None, first_bad)
}

#[inline(always)]
fn volume_task_body<T: Real>(
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    out: &mut [T],
) -> BadElement {
    let mut bad = None;
    for (bi, ob) in out.chunks_exact_mut(LANES).enumerate() {
        let b = first_block + bi;
        let conn = &eb.connectivity[b * 4 * LANES..(b + 1) * 4 * LANES];
        let ue = gather_displacements::<T, 4>(conn, u);
        let dh: &[[Lanes<T>; 3]; 4] = block_view(&eb.shape_derivatives[b * 4 * 3 * LANES..]);
        let f = super::element::deformation_gradient(&ue, dh);
        let j = super::element::det3(&f);
        (j * Lanes::load(&eb.quarter_volume[b * LANES..])).store(ob);
        if bad.is_none() {
            bad = (0..LANES)
                .find(|&l| !(j.0[l] > T::default()))
                .map(|l| (b * LANES + l, j.0[l].to_f64()));
        }
    }
    bad
}

#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
fn volume_task_avx2<T: Real>(
    eb: &ElementBlocks<T>,
    first_block: usize,
    u: &[T],
    out: &mut [T],
) -> BadElement {
    volume_task_body(eb, first_block, u, out)
}

/// T4ANP pass 1: current volume share J_e V_e / 4 of every element.
pub fn element_volume_shares<T: Real>(
    eb: &ElementBlocks<T>,
    u: &[T],
    shares: &mut [T],
) -> BadElement {
    let avx2 = has_avx2();
    shares
        .par_chunks_mut(BLOCKS_PER_TASK * LANES)
        .enumerate()
        .map(|(t, out)| {
            let first_block = t * BLOCKS_PER_TASK;
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            if avx2 {
                // SAFETY: AVX2 and FMA support was detected at run time.
                return unsafe { volume_task_avx2(eb, first_block, u, out) };
            }
            let _ = avx2;
            volume_task_body(eb, first_block, u, out)
        })
        .reduce(|| None, first_bad)
}

/// T4ANP pass 2: nodal dilatation J_n = (sum of J_e V_e / 4) / (sum of V_e / 4).
pub fn nodal_dilatation<T: Real>(
    eb: &ElementBlocks<T>,
    nodes: &NodeTable<T>,
    shares: &[T],
    nodal_j: &mut [T],
) {
    nodal_j
        .par_chunks_mut(NODES_PER_TASK)
        .enumerate()
        .for_each(|(t, out)| {
            for (i, nj) in out.iter_mut().enumerate() {
                let n = t * NODES_PER_TASK + i;
                let mut acc = T::default();
                for &s in nodes.slots_of(n) {
                    acc += shares[eb.slot_element(s as usize)];
                }
                // Orphan nodes (no element) keep J = 1.
                *nj = if nodes.inv_nodal_volume[n] > T::default() {
                    acc * nodes.inv_nodal_volume[n]
                } else {
                    T::from_f64(1.0)
                };
            }
        });
}

/// Constants of the central-difference update with mass-proportional damping
/// (DESIGN.md, NiftySim):
/// u+ = [h^2 (R - F) / M + 2 u - (1 - alpha h / 2) u-] / (1 + alpha h / 2).
#[derive(Clone, Copy, Debug)]
pub struct Integrator<T> {
    pub h2: T,
    pub previous_factor: T,
    pub inv_denominator: T,
    pub gravity: [T; 3],
    /// Any |u| above this is a runaway (diverged) state.
    pub runaway_m: T,
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn node_task_body<T: Real>(
    nodes: &NodeTable<T>,
    first: usize,
    forces: &[T],
    external: &[T],
    it: &Integrator<T>,
    u_prev: &[T],
    u_curr: &[T],
    u_next: &mut [T],
) -> Option<usize> {
    let mut bad = None;
    let two = T::from_f64(2.0);
    let count = u_next.len() / 3;
    let range = 3 * first..3 * (first + count);
    let (external, u_prev, u_curr) = (
        &external[range.clone()],
        &u_prev[range.clone()],
        &u_curr[range],
    );
    let (mass, inv_mass) = (
        &nodes.mass[first..first + count],
        &nodes.inv_mass[first..first + count],
    );
    for i in 0..count {
        let f = nodes.gather(forces, first + i);
        let hm = it.h2 * inv_mass[i];
        let mut ok = true;
        for c in 0..3 {
            let r = external[3 * i + c] + mass[i] * it.gravity[c];
            let v = (hm * (r - f[c]) + two * u_curr[3 * i + c]
                - it.previous_factor * u_prev[3 * i + c])
                * it.inv_denominator;
            u_next[3 * i + c] = v;
            let bounded = v < it.runaway_m && -v < it.runaway_m;
            ok &= bounded;
        }
        if !ok && bad.is_none() {
            bad = Some(first + i);
        }
    }
    bad
}

#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
fn node_task_avx2<T: Real>(
    nodes: &NodeTable<T>,
    first: usize,
    forces: &[T],
    external: &[T],
    it: &Integrator<T>,
    u_prev: &[T],
    u_curr: &[T],
    u_next: &mut [T],
) -> Option<usize> {
    node_task_body(nodes, first, forces, external, it, u_prev, u_curr, u_next)
}

/// Node pass: gathers the element force copies of every node and advances
/// it by one central-difference step into `u_next`. Returns the first node
/// whose new displacement is not finite or runs away.
#[allow(clippy::too_many_arguments)]
pub fn advance_nodes<T: Real>(
    nodes: &NodeTable<T>,
    forces: &[T],
    external: &[T],
    it: &Integrator<T>,
    u_prev: &[T],
    u_curr: &[T],
    u_next: &mut [T],
) -> Option<usize> {
    let avx2 = has_avx2();
    u_next
        .par_chunks_mut(NODES_PER_TASK * 3)
        .enumerate()
        .map(|(t, out)| {
            let first = t * NODES_PER_TASK;
            #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
            if avx2 {
                // SAFETY: AVX2 and FMA support was detected at run time.
                return unsafe {
                    node_task_avx2(nodes, first, forces, external, it, u_prev, u_curr, out)
                };
            }
            let _ = avx2;
            node_task_body(nodes, first, forces, external, it, u_prev, u_curr, out)
        })
        .reduce(
            || None,
            |a, b| match (a, b) {
                (Some(x), Some(y)) => Some(x.min(y)),
                (x, None) => x,
                (None, y) => y,
            },
        )
}
