//! The compute pipelines: WGSL sources specialised per model (nodes per
//! element, hourglass control, T4ANP) by prepending compile-time constants,
//! and explicit bind-group layouts (binding 0: run parameters, binding 1:
//! the per-step record at a dynamic offset, then the storage buffers).

use std::num::NonZeroU64;

use super::device::GpuDevice;
use super::error::GpuError;

const COMMON: &str = include_str!("shaders/common.wgsl");
const ELEMENT: &str = include_str!("shaders/element.wgsl");
const ANP: &str = include_str!("shaders/anp.wgsl");
const NODE: &str = include_str!("shaders/node.wgsl");
const BOUNDARY: &str = include_str!("shaders/boundary.wgsl");

/// Invocations per workgroup (shaders/common.wgsl `WORKGROUP`).
pub const WORKGROUP: u32 = 64;
/// Size of the `Params` uniform (shaders/common.wgsl), bytes.
pub const PARAMS_BYTES: u64 = 64;
/// Size of one `Step` record (shaders/common.wgsl), bytes.
pub const STEP_BYTES: u64 = 240;
/// Storage buffers the widest kernels (element, node) bind.
pub const STORAGE_BUFFERS_PER_KERNEL: u32 = 8;

/// wgpu's checks on the kernels, all but the forced loop bound: naga wraps
/// every loop in an iteration counter, which keeps the driver from
/// unrolling the loops over an element's nodes, so their arrays (u, dh,
/// the nodal forces) live in local memory instead of registers. With it
/// the H8 step took 2.4 times as long on an H100 (docs/PERFORMANCE.md).
/// Bounds checks on buffers and arrays stay on.
const RUNTIME_CHECKS: wgpu::ShaderRuntimeChecks = {
    let mut checks = wgpu::ShaderRuntimeChecks::checked();
    checks.force_loop_bounding = false;
    checks
};

/// How a kernel uses one binding.
#[derive(Clone, Copy)]
enum Access {
    Read,
    ReadWrite,
}

/// One pipeline and the layout its bind groups follow.
pub struct Kernel {
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

/// Every pipeline of one model.
pub struct Kernels {
    pub element: Kernel,
    /// T4ANP passes 1 and 2.
    pub volume_shares: Option<Kernel>,
    pub nodal_dilatation: Option<Kernel>,
    pub node: Kernel,
    pub pressure: Kernel,
    pub coupled: Kernel,
    pub probe: Kernel,
}

fn layout(gpu: &GpuDevice, label: &str, storage: &[(u32, Access)]) -> wgpu::BindGroupLayout {
    let uniform = |binding: u32, dynamic: bool, size: u64| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: NonZeroU64::new(size),
        },
        count: None,
    };
    let mut entries = vec![
        uniform(0, false, PARAMS_BYTES),
        uniform(1, true, STEP_BYTES),
    ];
    entries.extend(
        storage
            .iter()
            .map(|&(binding, access)| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: matches!(access, Access::Read),
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }),
    );
    gpu.device()
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        })
}

fn kernel(
    gpu: &GpuDevice,
    module: &wgpu::ShaderModule,
    entry: &'static str,
    storage: &[(u32, Access)],
) -> Kernel {
    let layout = layout(gpu, entry, storage);
    let pipeline_layout = gpu
        .device()
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
    let pipeline = gpu
        .device()
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
    Kernel { pipeline, layout }
}

/// The WGSL of one module for a model: constants, shared code, kernels.
pub fn source(body: &str, nodes_per_element: u32, hourglass: bool, anp: bool) -> String {
    format!("const NPE: u32 = {nodes_per_element}u;\nconst HOURGLASS: bool = {hourglass};\nconst ANP: bool = {anp};\n{COMMON}\n{body}")
}

impl Kernels {
    /// Compiles the pipelines; a shader the device rejects is an error, not a panic.
    pub fn new(
        gpu: &GpuDevice,
        nodes_per_element: u32,
        hourglass: bool,
        anp: bool,
    ) -> Result<Kernels, GpuError> {
        use Access::{Read, ReadWrite};
        Ok(gpu.scoped("compiling the TLED kernels", || {
            let module = |label: &str, body: &str| {
                let descriptor = wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(
                        source(body, nodes_per_element, hourglass, anp).into(),
                    ),
                };
                // SAFETY: RUNTIME_CHECKS drops only the loop bound that wgpu
                // adds against infinite loops, and every loop in these
                // kernels ends: each runs to NPE, 4 or 3, or over a range
                // read from the model's own tables, and its counter only grows.
                unsafe {
                    gpu.device()
                        .create_shader_module_trusted(descriptor, RUNTIME_CHECKS)
                }
            };
            // The element and node kernels bind the same arrays 2-9 and write the last two.
            let step_bindings = [
                (2, Read),
                (3, Read),
                (4, Read),
                (5, Read),
                (6, Read),
                (7, Read),
                (8, ReadWrite),
                (9, ReadWrite),
            ];
            let element = module("element.wgsl", ELEMENT);
            let node = module("node.wgsl", NODE);
            let boundary = module("boundary.wgsl", BOUNDARY);
            let (volume_shares, nodal_dilatation) = if anp {
                let m = module("anp.wgsl", ANP);
                (
                    Some(kernel(
                        gpu,
                        &m,
                        "volume_shares",
                        &[
                            (2, Read),
                            (3, Read),
                            (4, Read),
                            (5, Read),
                            (6, ReadWrite),
                            (7, ReadWrite),
                        ],
                    )),
                    Some(kernel(
                        gpu,
                        &m,
                        "nodal_dilatation",
                        &[(4, Read), (6, ReadWrite), (8, Read), (9, ReadWrite)],
                    )),
                )
            } else {
                (None, None)
            };
            Kernels {
                element: kernel(
                    gpu,
                    &element,
                    "element_forces",
                    &step_bindings,
                ),
                volume_shares,
                nodal_dilatation,
                node: kernel(
                    gpu,
                    &node,
                    "advance_nodes",
                    &step_bindings,
                ),
                pressure: kernel(
                    gpu,
                    &boundary,
                    "surface_pressure",
                    &[(2, Read), (3, Read), (4, Read), (5, ReadWrite)],
                ),
                coupled: kernel(gpu, &boundary, "hold_coupled", &[(2, Read), (7, ReadWrite)]),
                probe: kernel(
                    gpu,
                    &boundary,
                    "probe_forces",
                    &[(2, Read), (5, ReadWrite), (6, Read), (8, ReadWrite)],
                ),
            }
        })?)
    }
}

/// Workgroup counts (x, y) covering `count` invocations when x may not
/// exceed the device's per-dimension limit.
pub fn workgroups(count: u32, max_per_dimension: u32) -> (u32, u32) {
    let groups = count.div_ceil(WORKGROUP).max(1);
    if groups <= max_per_dimension {
        (groups, 1)
    } else {
        (max_per_dimension, groups.div_ceil(max_per_dimension))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every specialisation of every module parses and validates with naga
    /// (what wgpu runs before handing the shader to the driver).
    #[test]
    fn shaders_validate_for_every_element_kind() {
        for (npe, hourglass, anp) in [
            (8, true, false),
            (8, false, false),
            (4, false, false),
            (4, false, true),
        ] {
            for body in [ELEMENT, NODE, BOUNDARY, ANP] {
                let src = source(body, npe, hourglass, anp);
                let module = wgpu::naga::front::wgsl::parse_str(&src)
                    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
                wgpu::naga::valid::Validator::new(
                    wgpu::naga::valid::ValidationFlags::all(),
                    wgpu::naga::valid::Capabilities::empty(),
                )
                .validate(&module)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
            }
        }
    }

    #[test]
    fn large_dispatches_spill_into_y() {
        assert_eq!(workgroups(64, 65_535), (1, 1));
        assert_eq!(workgroups(65, 65_535), (2, 1));
        assert_eq!(workgroups(0, 65_535), (1, 1));
        let (x, y) = workgroups(10_000_000, 65_535);
        assert_eq!(x, 65_535);
        assert!(x as u64 * y as u64 * 64 >= 10_000_000);
    }
}
