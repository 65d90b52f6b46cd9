//! Memory traffic of one sub-step, from the buffers each kernel reads and
//! writes, for the bench's achieved-bandwidth figure. Gathers (displacements
//! read through the connectivity, force copies read through the node
//! table) are counted once per request, so this is what the kernels ask
//! for; caches can make the DRAM traffic lower.

use serde::{Deserialize, Serialize};

use super::buffers::ModelArrays;
use super::loads::CompiledLoads;

/// Bytes moved per sub-step by each kernel, and per element.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Traffic {
    pub element_kernel_bytes: u64,
    pub node_kernel_bytes: u64,
    /// T4ANP volume-share and nodal-dilatation passes (0 otherwise).
    pub anp_bytes: u64,
    /// Surface-pressure kernel (0 without pressure).
    pub pressure_bytes: u64,
    pub elements: u64,
}

impl Traffic {
    pub fn new(a: &ModelArrays, loads: &CompiledLoads) -> Traffic {
        let ne = a.element_count as u64;
        let nn = a.node_count as u64;
        let npe = a.nodes_per_element as u64;
        let slots = ne * npe;
        let w = |len: usize| 4 * len as u64;
        let u_gather = 12 * slots;
        let element_kernel_bytes = 4 * slots // connectivity
            + 12 * slots // shape derivatives
            + 4 * ne // weight
            + 12 * ne // coefficients
            + if a.hourglass { 4 * 32 * ne } else { 0 }
            + if a.anp { 4 * slots } else { 0 } // nodal dilatation gather
            + u_gather
            + 12 * slots; // force copies written
        let anp_bytes = if a.anp {
            (4 * slots + 12 * slots + 4 * ne + u_gather + 4 * ne) // pass 1
                + (4 * (nn + 1) + 4 * slots + 4 * slots + 4 * nn + 4 * nn) // pass 2
        } else {
            0
        };
        let node_kernel_bytes = 4 * (nn + 1) + 4 * slots // node table
            + 12 * slots // force copies gathered
            + 8 * nn // mass, 1 / mass
            + w(loads.node_loads.len()) // condition records (one word per free node)
            + 24 * nn // previous and current displacement
            + 12 * nn; // next displacement written
        let triangles = loads.triangle_count() as u64;
        let pressure_bytes = triangles * (20 + 3 * 24 + 36);
        Traffic {
            element_kernel_bytes,
            node_kernel_bytes,
            anp_bytes,
            pressure_bytes,
            elements: ne,
        }
    }

    pub fn bytes_per_substep(&self) -> u64 {
        self.element_kernel_bytes + self.node_kernel_bytes + self.anp_bytes + self.pressure_bytes
    }

    /// Bytes per element-step: what the bench multiplies by element-steps per second.
    pub fn bytes_per_element_step(&self) -> f64 {
        self.bytes_per_substep() as f64 / self.elements.max(1) as f64
    }
}

/// Peak memory bandwidth of known devices, GB/s, with the source. wgpu
/// cannot query it; other devices need the bench's `--peak-gbs`.
const KNOWN_PEAKS: [(&str, f64, &str); 3] = [
    ("H100 PCIe", 2000.0, "NVIDIA H100 PCIe datasheet: 2.0 TB/s"),
    ("H100", 3350.0, "NVIDIA H100 SXM5 datasheet: 3.35 TB/s"),
    ("H200", 4800.0, "NVIDIA H200 datasheet: 4.8 TB/s"),
];

/// The peak bandwidth of an adapter by name, when it is a known device.
pub fn known_peak_bandwidth(adapter_name: &str) -> Option<(f64, &'static str)> {
    KNOWN_PEAKS
        .iter()
        .find(|(name, _, _)| adapter_name.contains(name))
        .map(|&(_, gbs, source)| (gbs, source))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_devices_by_name() {
        assert_eq!(
            known_peak_bandwidth("NVIDIA H100 80GB HBM3").map(|p| p.0),
            Some(3350.0)
        );
        assert_eq!(
            known_peak_bandwidth("NVIDIA H100 PCIe").map(|p| p.0),
            Some(2000.0)
        );
        assert_eq!(
            known_peak_bandwidth("NVIDIA H200").map(|p| p.0),
            Some(4800.0)
        );
        assert_eq!(
            known_peak_bandwidth("llvmpipe (LLVM 19.1.7, 256 bits)"),
            None
        );
    }

    #[test]
    fn h8_element_kernel_moves_464_bytes_per_element() {
        use crate::generate::box_h8;
        use crate::loads::BoundaryConditions;
        use crate::material::Material;
        use crate::model::{MaterialRegion, ModelOptions, TledModel};
        let mesh = box_h8([1.0; 3], [4, 4, 4]);
        let region = MaterialRegion {
            element_set: None,
            material: Material::neo_hookean(1e3, 5e4),
            density_kg_m3: 1e3,
        };
        let model = TledModel::new(&mesh, &[region], &ModelOptions::default()).unwrap();
        let arrays = ModelArrays::new(&model);
        let loads =
            CompiledLoads::new(&BoundaryConditions::default(), model.node_count(), 0).unwrap();
        let t = Traffic::new(&arrays, &loads);
        // 8 node indices, 24 shape derivatives, weight, 3 coefficients,
        // 32 hourglass values, 8 gathered displacements, 24 forces written.
        assert_eq!(
            t.element_kernel_bytes,
            64 * (32 + 96 + 4 + 12 + 128 + 96 + 96)
        );
        // 125 nodes: table, 512 slots, gathered forces, mass, records, 3 displacement fields.
        assert_eq!(
            t.node_kernel_bytes,
            4 * 126 + 4 * 512 + 12 * 512 + 8 * 125 + 4 * 125 + 36 * 125
        );
        assert_eq!((t.anp_bytes, t.pressure_bytes), (0, 0));
    }
}
