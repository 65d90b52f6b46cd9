//! The model's constant data on the GPU, uploaded once: the CPU kernel's
//! structure-of-arrays element blocks as they are (8 elements per block,
//! field-major within the block, so neighbouring invocations read
//! neighbouring words), in f32, and the node tables. Sizes are checked
//! against the device's limits before anything is allocated.

use wgpu::util::DeviceExt;

use crate::kernel::blocks::KernelData;
use crate::kernel::lanes::Real;
use crate::model::{KernelModel, TledModel};

use super::device::GpuDevice;
use super::error::GpuError;

/// One planned buffer: its name (for errors) and size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Planned {
    pub name: &'static str,
    pub bytes: u64,
}

/// Refuses any buffer over the device's per-binding or per-buffer limit
/// (lavapipe: 128 MiB per storage binding), before allocating.
pub fn check_limits(
    gpu: &GpuDevice,
    planned: &[Planned],
    elements: usize,
    nodes: usize,
) -> Result<(), GpuError> {
    let limits = gpu.device().limits();
    let adapter = gpu.adapter_info().name.clone();
    if limits.max_storage_buffers_per_shader_stage < super::kernels::STORAGE_BUFFERS_PER_KERNEL {
        return Err(GpuError::LimitTooLow {
            what: "storage buffers",
            needed: super::kernels::STORAGE_BUFFERS_PER_KERNEL as u64,
            available: limits.max_storage_buffers_per_shader_stage as u64,
            adapter,
        });
    }
    for p in planned {
        for (limit_name, limit) in [
            (
                "largest storage binding (max_storage_buffer_binding_size)",
                limits.max_storage_buffer_binding_size,
            ),
            ("largest buffer (max_buffer_size)", limits.max_buffer_size),
        ] {
            if p.bytes > limit {
                return Err(GpuError::BufferTooLarge {
                    buffer: p.name,
                    bytes: p.bytes,
                    limit_name,
                    limit,
                    adapter: adapter.clone(),
                    elements,
                    nodes,
                });
            }
        }
    }
    Ok(())
}

/// The model arrays in the layout and precision the kernels read.
pub struct ModelArrays {
    pub nodes_per_element: u32,
    pub element_count: u32,
    pub node_count: u32,
    pub hourglass: bool,
    pub anp: bool,
    pub connectivity: Vec<u32>,
    pub shape_derivatives: Vec<f32>,
    pub weight: Vec<f32>,
    pub coefficients: Vec<f32>,
    /// H8 hourglass vectors; empty otherwise.
    pub hourglass_vectors: Vec<f32>,
    /// T4ANP V_e / 4 per element; empty otherwise.
    pub quarter_volume: Vec<f32>,
    /// [slot start per node (node_count + 1) | slots].
    pub node_table: Vec<u32>,
    /// Per node [mass, 1 / mass].
    pub node_mass: Vec<f32>,
    /// T4ANP 1 / (sum of V_e / 4) per node; empty otherwise.
    pub inv_nodal_volume: Vec<f32>,
    /// Reference coordinates, xyz per node (follower pressure; a viewer's vertex base).
    pub reference: Vec<f32>,
    /// Length of the element force-copy array, f32 words.
    pub force_copy_len: usize,
}

fn to_f32<T: Real>(v: &[T]) -> Vec<f32> {
    v.iter().map(|x| x.to_f64() as f32).collect()
}

fn arrays<T: Real>(k: &KernelData<T>, model: &TledModel) -> ModelArrays {
    let eb = &k.elements;
    let nt = &k.nodes;
    let mut node_table = nt.slot_start.clone();
    node_table.extend_from_slice(&nt.slots);
    ModelArrays {
        nodes_per_element: eb.nodes_per_element as u32,
        element_count: eb.element_count as u32,
        node_count: model.node_count() as u32,
        hourglass: !eb.hourglass.is_empty(),
        anp: model.uses_anp(),
        connectivity: eb.connectivity.clone(),
        shape_derivatives: to_f32(&eb.shape_derivatives),
        weight: to_f32(&eb.weight),
        coefficients: to_f32(&eb.coefficients),
        hourglass_vectors: to_f32(&eb.hourglass),
        quarter_volume: to_f32(&eb.quarter_volume),
        node_table,
        node_mass: nt
            .mass
            .iter()
            .zip(&nt.inv_mass)
            .flat_map(|(m, im)| [m.to_f64() as f32, im.to_f64() as f32])
            .collect(),
        inv_nodal_volume: to_f32(&nt.inv_nodal_volume),
        reference: model
            .mesh()
            .nodes
            .iter()
            .flat_map(|p| p.map(|c| c as f32))
            .collect(),
        force_copy_len: eb.force_copy_len(),
    }
}

impl ModelArrays {
    /// The kernel arrays of a model of either precision, in f32.
    pub fn new(model: &TledModel) -> ModelArrays {
        match model.kernel() {
            KernelModel::F32(k) => arrays(k, model),
            KernelModel::F64(k) => arrays(k, model),
        }
    }

    /// Every buffer the model needs, with its size.
    pub fn planned(&self) -> Vec<Planned> {
        let b = |name, words: usize| Planned {
            name,
            bytes: 4 * words.max(1) as u64,
        };
        vec![
            b("element connectivity", self.connectivity.len()),
            b("shape derivative", self.shape_derivatives.len()),
            b("integration weight", self.weight.len()),
            b("material coefficient", self.coefficients.len()),
            b("hourglass vector", self.hourglass_vectors.len()),
            b("element volume", self.quarter_volume.len()),
            b("node-to-slot table", self.node_table.len()),
            b("nodal mass", self.node_mass.len()),
            b("nodal volume", self.inv_nodal_volume.len()),
            b("reference coordinate", self.reference.len()),
        ]
    }
}

/// A storage buffer holding `data` (at least one word: empty bindings are invalid).
pub fn storage<T: bytemuck::Pod + Default>(
    gpu: &GpuDevice,
    label: &str,
    data: &[T],
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let one = [T::default()];
    let contents: &[T] = if data.is_empty() { &one } else { data };
    gpu.device()
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(contents),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST
                | extra,
        })
}

/// The constant model buffers.
pub struct ModelBuffers {
    pub connectivity: wgpu::Buffer,
    pub shape_derivatives: wgpu::Buffer,
    pub weight: wgpu::Buffer,
    pub coefficients: wgpu::Buffer,
    pub hourglass_vectors: wgpu::Buffer,
    pub quarter_volume: wgpu::Buffer,
    pub node_table: wgpu::Buffer,
    pub node_mass: wgpu::Buffer,
    pub inv_nodal_volume: wgpu::Buffer,
    pub reference: wgpu::Buffer,
}

impl ModelBuffers {
    pub fn upload(gpu: &GpuDevice, a: &ModelArrays) -> Result<ModelBuffers, GpuError> {
        let none = wgpu::BufferUsages::empty();
        Ok(gpu.scoped("uploading the model", || ModelBuffers {
            connectivity: storage(gpu, "element connectivity", &a.connectivity, none),
            shape_derivatives: storage(gpu, "shape derivatives", &a.shape_derivatives, none),
            weight: storage(gpu, "integration weights", &a.weight, none),
            coefficients: storage(gpu, "material coefficients", &a.coefficients, none),
            hourglass_vectors: storage(gpu, "hourglass vectors", &a.hourglass_vectors, none),
            quarter_volume: storage(gpu, "element volumes", &a.quarter_volume, none),
            node_table: storage(gpu, "node-to-slot table", &a.node_table, none),
            node_mass: storage(gpu, "nodal masses", &a.node_mass, none),
            inv_nodal_volume: storage(gpu, "nodal volumes", &a.inv_nodal_volume, none),
            reference: storage(
                gpu,
                "reference coordinates",
                &a.reference,
                wgpu::BufferUsages::VERTEX,
            ),
        })?)
    }
}
