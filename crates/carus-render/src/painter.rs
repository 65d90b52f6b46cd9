//! The drawing itself, independent of where it lands: pipelines, mesh
//! buffers and camera uniforms. The offscreen renderer draws into a
//! texture with it; a viewer draws into its window's render pass the same way.

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::camera::Camera;
use crate::colour::{srgba_to_linear, ColourMap};
use crate::error::RenderError;
use crate::mesh::RenderMesh;
use crate::scene::{Lights, Scene};

/// The attachments a painter draws into: its pipelines are built for them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TargetFormat {
    /// Colour attachment. With an sRGB format the hardware encodes the
    /// shader's linear light; with a plain one (as egui's window surfaces
    /// use) the shader encodes it itself.
    pub colour: wgpu::TextureFormat,
    /// Depth attachment.
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel.
    pub sample_count: u32,
}

impl TargetFormat {
    /// Offscreen pictures: 8-bit sRGB RGBA (the PNG's bytes), 32-bit depth,
    /// 4x multisampling, which Vulkan, Metal and DX12 all offer for these
    /// formats (WebGPU requires it).
    pub const PICTURE: TargetFormat = TargetFormat {
        colour: wgpu::TextureFormat::Rgba8UnormSrgb,
        depth: wgpu::TextureFormat::Depth32Float,
        sample_count: 4,
    };
}

/// Per-picture uniforms (camera and lights), laid out as `Frame` in mesh.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameUniform {
    view_proj: [[f32; 4]; 4],
    view: [[f32; 4]; 4],
    key: [f32; 4],
    fill: [f32; 4],
    shading: [f32; 4],
}

/// Per-mesh uniforms, laid out as `Material` in mesh.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MaterialUniform {
    colour: [f32; 4],
    scalar: [f32; 4],
}

/// A mesh uploaded to the GPU, ready to be painted.
pub struct GpuMesh {
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    scalars: wgpu::Buffer,
    indices: wgpu::Buffer,
    vertex_count: usize,
    index_count: u32,
    material_uniform: wgpu::Buffer,
    material: wgpu::BindGroup,
    transparent: bool,
    /// Centre of its bounds: the sort key of transparent meshes.
    centre: Vec3,
}

/// What the GPU buffers of a mesh hold beyond its positions and indices.
struct MeshData {
    normals: Vec<[f32; 3]>,
    /// One per vertex; zeros when the mesh has no scalar field.
    scalars: Vec<f32>,
    material: MaterialUniform,
    centre: Vec3,
}

impl MeshData {
    fn of(mesh: &RenderMesh, index: usize) -> Result<Self, RenderError> {
        mesh.validate(index)?;
        let (scalars, scalar) = match &mesh.scalars {
            Some(field) => {
                let row = (field.colour_map.row() as f32 + 0.5) / ColourMap::ALL.len() as f32;
                (
                    field.values.clone(),
                    [field.range[0], field.range[1], 1.0, row],
                )
            }
            None => (vec![0.0; mesh.positions.len()], [0.0, 1.0, 0.0, 0.0]),
        };
        let centre = mesh
            .bounds()
            .map(|b| b.centre())
            .ok_or_else(|| RenderError::InvalidMesh {
                mesh: index,
                name: mesh.name.clone(),
                problem: "has no vertices".into(),
            })?;
        Ok(Self {
            normals: mesh.vertex_normals(),
            scalars,
            material: MaterialUniform {
                colour: srgba_to_linear(mesh.colour),
                scalar,
            },
            centre,
        })
    }
}

/// Pipelines and shared bindings for one colour format and sample count.
pub struct MeshPainter {
    opaque: wgpu::RenderPipeline,
    transparent_back_faces: wgpu::RenderPipeline,
    transparent_front_faces: wgpu::RenderPipeline,
    material_layout: wgpu::BindGroupLayout,
    frame_uniform: wgpu::Buffer,
    frame_bindings: wgpu::BindGroup,
}

impl MeshPainter {
    /// Builds the pipelines for render passes with the attachments of `target`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, target: TargetFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("carus-render mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/mesh.wgsl").into()),
        });
        let uniform_entry = |binding, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("carus-render frame"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("carus-render material"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::FRAGMENT)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("carus-render meshes"),
            bind_group_layouts: &[Some(&frame_layout), Some(&material_layout)],
            immediate_size: 0,
        });

        let frame_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("carus-render frame uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let colour_maps = colour_map_texture(device, queue);
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("carus-render colour maps"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let frame_bindings = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("carus-render frame"),
            layout: &frame_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame_uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        &colour_maps.create_view(&wgpu::TextureViewDescriptor::default()),
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });

        let encode_srgb = [(
            "encode_srgb",
            if target.colour.is_srgb() { 0.0 } else { 1.0 },
        )];
        let fragment_options = wgpu::PipelineCompilationOptions {
            constants: &encode_srgb,
            ..Default::default()
        };
        let pipeline = |label, cull_mode, blend, depth_write| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &VERTEX_BUFFERS,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: target.depth,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: target.sample_count,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some("fs_main"),
                    compilation_options: fragment_options.clone(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: target.colour,
                        blend: Some(blend),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            // Opaque meshes may be open (a pelvic floor sheet): no culling,
            // back faces lit from their own side by the shader.
            opaque: pipeline("carus-render opaque", None, wgpu::BlendState::REPLACE, true),
            // A transparent mesh is drawn in two passes, its far side first,
            // so that its own layers blend in order for convex-ish shapes.
            transparent_back_faces: pipeline(
                "carus-render transparent back faces",
                Some(wgpu::Face::Front),
                wgpu::BlendState::ALPHA_BLENDING,
                false,
            ),
            transparent_front_faces: pipeline(
                "carus-render transparent front faces",
                Some(wgpu::Face::Back),
                wgpu::BlendState::ALPHA_BLENDING,
                false,
            ),
            material_layout,
            frame_uniform,
            frame_bindings,
        }
    }

    /// Uploads a mesh (checked first; `index` names it in errors).
    pub fn upload(
        &self,
        device: &wgpu::Device,
        mesh: &RenderMesh,
        index: usize,
    ) -> Result<GpuMesh, RenderError> {
        let data = MeshData::of(mesh, index)?;
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: usage | wgpu::BufferUsages::COPY_DST,
            })
        };
        let vertex = wgpu::BufferUsages::VERTEX;
        let material_uniform = buffer(
            "carus-render material uniform",
            bytemuck::bytes_of(&data.material),
            wgpu::BufferUsages::UNIFORM,
        );
        Ok(GpuMesh {
            positions: buffer(
                "carus-render positions",
                bytemuck::cast_slice(&mesh.positions),
                vertex,
            ),
            normals: buffer(
                "carus-render normals",
                bytemuck::cast_slice(&data.normals),
                vertex,
            ),
            scalars: buffer(
                "carus-render scalars",
                bytemuck::cast_slice(&data.scalars),
                vertex,
            ),
            indices: buffer(
                "carus-render indices",
                bytemuck::cast_slice(&mesh.indices),
                wgpu::BufferUsages::INDEX,
            ),
            vertex_count: mesh.positions.len(),
            index_count: mesh.indices.len() as u32,
            material: device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("carus-render material"),
                layout: &self.material_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: material_uniform.as_entire_binding(),
                }],
            }),
            material_uniform,
            transparent: mesh.is_transparent(),
            centre: data.centre,
        })
    }

    /// Replaces an uploaded mesh's vertices, triangles, colour and scalars
    /// in place (a moving fetus, a deforming pelvic floor), without new
    /// buffers. The new mesh must have as many vertices and triangles as
    /// the uploaded one.
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        uploaded: &mut GpuMesh,
        mesh: &RenderMesh,
        index: usize,
    ) -> Result<(), RenderError> {
        let data = MeshData::of(mesh, index)?;
        if mesh.positions.len() != uploaded.vertex_count
            || mesh.indices.len() != uploaded.index_count as usize
        {
            return Err(RenderError::InvalidMesh {
                mesh: index,
                name: mesh.name.clone(),
                problem: format!(
                    "has {} vertices and {} indices but was uploaded with {} and {}: upload it anew",
                    mesh.positions.len(),
                    mesh.indices.len(),
                    uploaded.vertex_count,
                    uploaded.index_count
                ),
            });
        }
        queue.write_buffer(
            &uploaded.positions,
            0,
            bytemuck::cast_slice(&mesh.positions),
        );
        queue.write_buffer(&uploaded.normals, 0, bytemuck::cast_slice(&data.normals));
        queue.write_buffer(&uploaded.scalars, 0, bytemuck::cast_slice(&data.scalars));
        queue.write_buffer(&uploaded.indices, 0, bytemuck::cast_slice(&mesh.indices));
        queue.write_buffer(
            &uploaded.material_uniform,
            0,
            bytemuck::bytes_of(&data.material),
        );
        uploaded.transparent = mesh.is_transparent();
        uploaded.centre = data.centre;
        Ok(())
    }

    /// Uploads every mesh of a scene.
    pub fn upload_scene(
        &self,
        device: &wgpu::Device,
        scene: &Scene,
    ) -> Result<Vec<GpuMesh>, RenderError> {
        scene
            .meshes
            .iter()
            .enumerate()
            .map(|(i, mesh)| self.upload(device, mesh, i))
            .collect()
    }

    /// Writes the camera and lights for a target of `aspect` (width / height).
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera, lights: &Lights, aspect: f32) {
        let towards = |light: &crate::scene::DirectionalLight| {
            let d = Vec3::from(light.towards_light)
                .try_normalize()
                .unwrap_or(Vec3::Z);
            [d.x, d.y, d.z, light.intensity]
        };
        let frame = FrameUniform {
            view_proj: camera.view_projection(aspect).to_cols_array_2d(),
            view: camera.view_matrix().to_cols_array_2d(),
            key: towards(&lights.key),
            fill: towards(&lights.fill),
            shading: [
                lights.headlight,
                lights.ambient,
                lights.rim,
                if camera.is_orthographic() { 0.0 } else { 1.0 },
            ],
        };
        queue.write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&frame));
    }

    /// Records the draws into a pass: opaque meshes, then transparent
    /// ones from the farthest to the nearest (by the centre of their bounds).
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'_>, meshes: &[GpuMesh], camera: &Camera) {
        pass.set_bind_group(0, &self.frame_bindings, &[]);
        pass.set_pipeline(&self.opaque);
        for mesh in meshes.iter().filter(|m| !m.transparent) {
            draw(pass, mesh);
        }
        let mut transparent: Vec<&GpuMesh> = meshes.iter().filter(|m| m.transparent).collect();
        transparent.sort_by(|a, b| {
            camera
                .depth_of(b.centre)
                .total_cmp(&camera.depth_of(a.centre))
        });
        for mesh in transparent {
            pass.set_pipeline(&self.transparent_back_faces);
            draw(pass, mesh);
            pass.set_pipeline(&self.transparent_front_faces);
            draw(pass, mesh);
        }
    }
}

/// Positions, normals and scalars in three buffers (structure of arrays),
/// so a deforming mesh can replace its positions alone.
const VERTEX_BUFFERS: [Option<wgpu::VertexBufferLayout<'static>>; 3] = [
    Some(wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        }],
    }),
    Some(wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 1,
        }],
    }),
    Some(wgpu::VertexBufferLayout {
        array_stride: 4,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &[wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 0,
            shader_location: 2,
        }],
    }),
];

fn draw(pass: &mut wgpu::RenderPass<'_>, mesh: &GpuMesh) {
    pass.set_bind_group(1, &mesh.material, &[]);
    pass.set_vertex_buffer(0, mesh.positions.slice(..));
    pass.set_vertex_buffer(1, mesh.normals.slice(..));
    pass.set_vertex_buffer(2, mesh.scalars.slice(..));
    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..mesh.index_count, 0, 0..1);
}

/// Every colour map as one row of an sRGB texture (sampling returns linear light).
fn colour_map_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::Texture {
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("carus-render colour maps"),
            size: wgpu::Extent3d {
                width: ColourMap::RESOLUTION as u32,
                height: ColourMap::ALL.len() as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &ColourMap::lookup_table(),
    )
}
