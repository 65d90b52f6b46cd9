//! The constant model data of the step loop, laid out for the kernels.
//!
//! Elements are stored in blocks of [`LANES`] elements, each field
//! lane-major (`[field][lane]`), so one field of a block is one contiguous
//! 8-wide load. The per-element force copies use the same layout, and every
//! node owns a list of the slots (element, local node) that touch it, so the
//! gather is race-free and its summation order fixed (NiftySim's scheme).
//! A GPU backend uploads these arrays as they are.

use super::lanes::{Real, LANES};

/// Element data in blocks of `LANES` elements. Unused lanes of the last block
/// have zero weight and zero moduli, so they give zero force and J = 1.
#[derive(Debug, Clone)]
pub struct ElementBlocks<T> {
    pub nodes_per_element: usize,
    pub element_count: usize,
    pub block_count: usize,
    /// `[(b * npe + a) * LANES + l]`: node index of local node a.
    pub connectivity: Vec<u32>,
    /// `[((b * npe + a) * 3 + i) * LANES + l]`: dh_a/dX_i in the reference configuration.
    pub shape_derivatives: Vec<T>,
    /// `[b * LANES + l]`: integration weight, the element volume.
    pub weight: Vec<T>,
    /// `[(b * 3 + k) * LANES + l]`: c10, c01, kappa of the isotropic kernel.
    pub coefficients: Vec<T>,
    /// H8 with hourglass control: `[((b * 4 + g) * 8 + a) * LANES + l]`,
    /// sqrt(k) gamma_g,a; empty otherwise.
    pub hourglass: Vec<T>,
    /// T4ANP: `[b * LANES + l]`, V / 4 of the element; empty otherwise.
    pub quarter_volume: Vec<T>,
}

/// Per-element inputs in f64, as the model builder computes them.
pub struct ElementInput<'a> {
    pub nodes: &'a [u32],
    pub shape_derivatives: &'a [[f64; 3]],
    pub weight: f64,
    pub coefficients: [f64; 3],
    pub hourglass: Option<&'a [[f64; 8]; 4]>,
    pub volume: f64,
}

impl<T: Real> ElementBlocks<T> {
    pub fn new(nodes_per_element: usize, element_count: usize, hourglass: bool, anp: bool) -> Self {
        let block_count = element_count.div_ceil(LANES);
        let slots = block_count * LANES;
        ElementBlocks {
            nodes_per_element,
            element_count,
            block_count,
            connectivity: vec![0; slots * nodes_per_element],
            shape_derivatives: vec![T::default(); slots * nodes_per_element * 3],
            weight: vec![T::default(); slots],
            coefficients: vec![T::default(); slots * 3],
            hourglass: if hourglass {
                vec![T::default(); slots * 32]
            } else {
                Vec::new()
            },
            quarter_volume: if anp {
                vec![T::default(); slots]
            } else {
                Vec::new()
            },
        }
    }

    /// Writes element `e` into its block and lane.
    pub fn set(&mut self, e: usize, input: &ElementInput) {
        let npe = self.nodes_per_element;
        let (b, l) = (e / LANES, e % LANES);
        for a in 0..npe {
            self.connectivity[(b * npe + a) * LANES + l] = input.nodes[a];
            for i in 0..3 {
                self.shape_derivatives[((b * npe + a) * 3 + i) * LANES + l] =
                    T::from_f64(input.shape_derivatives[a][i]);
            }
        }
        self.weight[b * LANES + l] = T::from_f64(input.weight);
        for k in 0..3 {
            self.coefficients[(b * 3 + k) * LANES + l] = T::from_f64(input.coefficients[k]);
        }
        if let (Some(hg), false) = (input.hourglass, self.hourglass.is_empty()) {
            for g in 0..4 {
                for a in 0..8 {
                    self.hourglass[((b * 4 + g) * 8 + a) * LANES + l] = T::from_f64(hg[g][a]);
                }
            }
        }
        if !self.quarter_volume.is_empty() {
            self.quarter_volume[b * LANES + l] = T::from_f64(input.volume / 4.0);
        }
    }

    /// Offset in the force-copy array of (element e, local node a), x component;
    /// y and z follow at +LANES and +2 LANES.
    #[inline]
    pub fn force_slot(&self, e: usize, a: usize) -> usize {
        let (b, l) = (e / LANES, e % LANES);
        (b * self.nodes_per_element + a) * 3 * LANES + l
    }

    /// Element of a force slot (inverse of [`Self::force_slot`]).
    #[inline]
    pub fn slot_element(&self, slot: usize) -> usize {
        // Constant divisors (multiplications) instead of a division by a run-time value.
        let block = match self.nodes_per_element {
            4 => slot / (4 * 3 * LANES),
            _ => slot / (8 * 3 * LANES),
        };
        block * LANES + slot % LANES
    }

    /// Length of the per-element force-copy array.
    pub fn force_copy_len(&self) -> usize {
        self.block_count * LANES * self.nodes_per_element * 3
    }

    /// Node `a` of element `e`.
    #[inline]
    pub fn node(&self, e: usize, a: usize) -> usize {
        self.connectivity[(e / LANES * self.nodes_per_element + a) * LANES + e % LANES] as usize
    }

    #[inline]
    pub fn shape_derivative(&self, e: usize, a: usize, i: usize) -> f64 {
        self.shape_derivatives
            [((e / LANES * self.nodes_per_element + a) * 3 + i) * LANES + e % LANES]
            .to_f64()
    }

    #[inline]
    pub fn element_weight(&self, e: usize) -> f64 {
        self.weight[e].to_f64()
    }

    #[inline]
    pub fn coefficient(&self, e: usize, k: usize) -> f64 {
        self.coefficients[(e / LANES * 3 + k) * LANES + e % LANES].to_f64()
    }

    #[inline]
    pub fn hourglass_vector(&self, e: usize, g: usize, a: usize) -> f64 {
        self.hourglass[((e / LANES * 4 + g) * 8 + a) * LANES + e % LANES].to_f64()
    }
}

/// Node data: lumped masses and the node-to-force-slot gather table.
#[derive(Debug, Clone)]
pub struct NodeTable<T> {
    pub mass: Vec<T>,
    /// 1 / mass, 0 for a node no element touches (it never moves by itself).
    pub inv_mass: Vec<T>,
    /// CSR start of each node's slots; `slot_start.len() == nodes + 1`.
    pub slot_start: Vec<u32>,
    /// Force-copy offsets (x component) of the slots touching each node, in
    /// increasing element order.
    pub slots: Vec<u32>,
    /// T4ANP: 1 / (sum of V/4 over the elements sharing the node); empty otherwise.
    pub inv_nodal_volume: Vec<T>,
}

impl<T: Real> NodeTable<T> {
    #[inline]
    pub fn slots_of(&self, n: usize) -> &[u32] {
        &self.slots[self.slot_start[n] as usize..self.slot_start[n + 1] as usize]
    }

    /// Sum of the element force copies at node n, in the fixed slot order.
    #[inline(always)]
    pub fn gather(&self, forces: &[T], n: usize) -> [T; 3] {
        let mut f = [T::default(); 3];
        for &s in self.slots_of(n) {
            let s = s as usize;
            let copy = &forces[s..s + 2 * LANES + 1];
            f[0] += copy[0];
            f[1] += copy[LANES];
            f[2] += copy[2 * LANES];
        }
        f
    }
}

/// Everything the kernels read, in one precision.
#[derive(Debug, Clone)]
pub struct KernelData<T> {
    pub elements: ElementBlocks<T>,
    pub nodes: NodeTable<T>,
}

impl<T: Real> KernelData<T> {
    /// Bytes of kernel data (model arrays only).
    pub fn bytes(&self) -> usize {
        let t = std::mem::size_of::<T>();
        let e = &self.elements;
        let n = &self.nodes;
        e.connectivity.len() * 4
            + (e.shape_derivatives.len()
                + e.weight.len()
                + e.coefficients.len()
                + e.hourglass.len()
                + e.quarter_volume.len())
                * t
            + (n.mass.len() + n.inv_mass.len() + n.inv_nodal_volume.len()) * t
            + (n.slot_start.len() + n.slots.len()) * 4
    }
}
