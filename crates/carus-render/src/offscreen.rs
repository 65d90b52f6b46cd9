//! Pictures without a window: the painter draws into a multisampled
//! texture, which is resolved and read back row by row.


use crate::camera::Camera;
use crate::colour::srgb_to_linear;
use crate::error::RenderError;
use crate::gpu::{AdapterChoice, GpuContext, GPU_TIMEOUT};
use crate::mesh::RenderMesh;
use crate::painter::{GpuMesh, MeshPainter, TargetFormat};
use crate::picture::Image;
use crate::scene::{check_background, Lights, Scene};

/// A scene whose meshes live on the GPU, ready to be drawn from any camera.
pub struct GpuScene {
    meshes: Vec<GpuMesh>,
    /// Lighting.
    pub lights: Lights,
    /// sRGB background colour with alpha.
    pub background: [f32; 4],
}

/// Draws scenes into RGBA8 pictures.
pub struct Renderer {
    gpu: GpuContext,
    painter: MeshPainter,
    format: TargetFormat,
    /// Kept between pictures of the same size.
    target: Option<OffscreenTarget>,
}

impl Renderer {
    /// Opens the best adapter (a real GPU, else a software one such as
    /// lavapipe) and builds the pipelines. Fails, never panics, when no
    /// adapter exists, with the packages that provide one in the message.
    pub fn new_headless() -> Result<Self, RenderError> {
        Self::with_context(GpuContext::headless(AdapterChoice::BestAvailable)?)
    }

    /// Draws with a device opened elsewhere.
    pub fn with_context(gpu: GpuContext) -> Result<Self, RenderError> {
        Self::with_format(gpu, TargetFormat::PICTURE)
    }

    /// `format.colour` must be an RGBA8 format: the readback keeps the byte order.
    fn with_format(gpu: GpuContext, format: TargetFormat) -> Result<Self, RenderError> {
        // A device that cannot multisample these formats fails in the scope.
        let painter = gpu.scoped("building the mesh pipelines", || {
            MeshPainter::new(gpu.device(), gpu.queue(), format)
        })?;
        Ok(Self {
            gpu,
            painter,
            format,
            target: None,
        })
    }

    /// The device, for sharing with other GPU work.
    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    /// Draws `scene` seen by `camera` into a `width` x `height` picture.
    pub fn render(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Image, RenderError> {
        let uploaded = self.upload(scene)?;
        self.render_uploaded(&uploaded, camera, width, height)
    }

    /// Uploads a scene once, to draw it many times (several views, or key
    /// moments where only the fetus moves: see `update_mesh`).
    pub fn upload(&self, scene: &Scene) -> Result<GpuScene, RenderError> {
        scene.validate()?;
        let meshes = self.gpu.scoped("uploading the meshes", || {
            self.painter.upload_scene(self.gpu.device(), scene)
        })??;
        Ok(GpuScene {
            meshes,
            lights: scene.lights,
            background: scene.background,
        })
    }

    /// Replaces mesh `index` of an uploaded scene by `mesh`, which must have
    /// as many vertices and triangles (a re-posed or deformed copy).
    pub fn update_mesh(
        &self,
        scene: &mut GpuScene,
        index: usize,
        mesh: &RenderMesh,
    ) -> Result<(), RenderError> {
        let count = scene.meshes.len();
        let uploaded = scene
            .meshes
            .get_mut(index)
            .ok_or_else(|| RenderError::InvalidMesh {
                mesh: index,
                name: mesh.name.clone(),
                problem: format!("the uploaded scene has only {count} meshes"),
            })?;
        self.gpu.scoped("updating a mesh", || {
            self.painter.update(self.gpu.queue(), uploaded, mesh, index)
        })?
    }

    /// Draws an uploaded scene seen by `camera` into a `width` x `height` picture.
    pub fn render_uploaded(
        &mut self,
        scene: &GpuScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Image, RenderError> {
        let max = self.gpu.device().limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::InvalidSize { width, height, max });
        }
        check_background(scene.background)?;
        let target = match self
            .target
            .take()
            .filter(|t| (t.width, t.height) == (width, height))
        {
            Some(target) => target,
            None => self.gpu.scoped("creating the picture target", || {
                OffscreenTarget::new(self.gpu.device(), width, height, self.format)
            })?,
        };
        let picture = self.draw(scene, camera, &target);
        // Kept for the next picture of the same size even after a failure.
        self.target = Some(target);
        picture
    }

    fn draw(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        target: &OffscreenTarget,
    ) -> Result<Image, RenderError> {
        let (width, height) = (target.width, target.height);
        // The clear colour is written as given: in linear light for an sRGB
        // target (which encodes it), already encoded for a plain one.
        let encode = |c: f32| {
            if self.format.colour.is_srgb() {
                srgb_to_linear(c) as f64
            } else {
                c as f64
            }
        };
        let [r, g, b, a] = scene.background;
        let clear = wgpu::Color {
            r: encode(r),
            g: encode(g),
            b: encode(b),
            a: a as f64,
        };
        let submission = self.gpu.scoped("drawing the picture", || {
            self.painter.prepare(
                self.gpu.queue(),
                camera,
                &scene.lights,
                width as f32 / height as f32,
            );
            let mut encoder =
                self.gpu
                    .device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("carus-render picture"),
                    });
            {
                let (view, resolve_target) = match &target.multisampled {
                    Some(msaa) => (msaa, Some(&target.resolved)),
                    None => (&target.resolved, None),
                };
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("carus-render meshes"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(clear),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &target.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                self.painter.paint(&mut pass, &scene.meshes, camera);
            }
            target.copy_to_readback(&mut encoder);
            self.gpu.queue().submit([encoder.finish()])
        })?;
        self.gpu.wait(Some(submission), "drawing the picture", GPU_TIMEOUT)?;
        target.read_back(&self.gpu)
    }
}

/// The textures a picture is drawn into, and the buffer it is read through.
struct OffscreenTarget {
    width: u32,
    height: u32,
    /// Multisampled colour, resolved into `resolved`; `None` with one sample.
    multisampled: Option<wgpu::TextureView>,
    resolved_texture: wgpu::Texture,
    resolved: wgpu::TextureView,
    depth: wgpu::TextureView,
    readback: wgpu::Buffer,
    /// Bytes per row in `readback`: rows are padded to COPY_BYTES_PER_ROW_ALIGNMENT.
    padded_row: u32,
}

impl OffscreenTarget {
    fn new(device: &wgpu::Device, width: u32, height: u32, format: TargetFormat) -> Self {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let texture = |label, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let multisampled = (format.sample_count > 1).then(|| {
            view(&texture(
                "carus-render multisampled colour",
                format.colour,
                format.sample_count,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            ))
        });
        let resolved_texture = texture(
            "carus-render picture",
            format.colour,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = view(&texture(
            "carus-render depth",
            format.depth,
            format.sample_count,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        ));
        let padded_row = padded_bytes_per_row(width);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("carus-render readback"),
            size: padded_row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Self {
            width,
            height,
            multisampled,
            resolved: view(&resolved_texture),
            resolved_texture,
            depth,
            readback,
            padded_row,
        }
    }

    fn copy_to_readback(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_texture_to_buffer(
            self.resolved_texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Maps the readback buffer and strips the row padding.
    fn read_back(&self, gpu: &GpuContext) -> Result<Image, RenderError> {
        let mapped = gpu.map_read(&self.readback, "reading the picture back", GPU_TIMEOUT)?;
        let row = self.width as usize * 4;
        let mut pixels = Vec::with_capacity(row * self.height as usize);
        for padded in mapped.chunks_exact(self.padded_row as usize) {
            pixels.extend_from_slice(&padded[..row]);
        }
        Image::from_rgba(self.width, self.height, pixels)
    }
}

/// Row length in a buffer that a texture is copied into: wgpu requires a
/// multiple of COPY_BYTES_PER_ROW_ALIGNMENT (256 bytes).
fn padded_bytes_per_row(width: u32) -> u32 {
    let unpadded = width * 4;
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_and_single_sample_targets_get_the_same_bytes() {
        use crate::{Camera, RenderMesh, Scene, View};
        // A triangle facing the anterior camera, drawn in its flat colour by
        // ambient light alone, over a mid-grey background.
        let mesh = RenderMesh::new(
            "sheet",
            vec![[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]],
            vec![0, 2, 1],
            [0.2, 0.5, 0.8],
        );
        let mut scene = Scene::new(vec![mesh]);
        scene.lights.key.intensity = 0.0;
        scene.lights.fill.intensity = 0.0;
        scene.lights.headlight = 0.0;
        scene.lights.rim = 0.0;
        scene.lights.ambient = 1.0;
        scene.background = [0.5, 0.5, 0.5, 1.0];
        let camera = Camera::standard(View::Anterior, &scene.bounds().unwrap());
        let plain = TargetFormat {
            colour: wgpu::TextureFormat::Rgba8Unorm,
            ..TargetFormat::PICTURE
        };
        let single_sample = TargetFormat {
            sample_count: 1,
            ..TargetFormat::PICTURE
        };
        let pictures = [TargetFormat::PICTURE, plain, single_sample].map(|format| {
            let gpu = GpuContext::headless(AdapterChoice::BestAvailable).unwrap_or_else(|e| panic!("{e}"));
            let mut renderer = Renderer::with_format(gpu, format).unwrap();
            renderer.render(&scene, &camera, 32, 32).unwrap()
        });
        let [srgb, plain, single] = &pictures;
        for other in [plain, single] {
            for (x, y) in [(16, 16), (0, 0)] {
                let (a, b) = (srgb.pixel(x, y).unwrap(), other.pixel(x, y).unwrap());
                assert!(
                    a.iter().zip(b).all(|(p, q)| p.abs_diff(q) <= 2),
                    "({x}, {y}): {a:?} vs {b:?}"
                );
            }
        }
        let near = |p: [u8; 4], q: [u8; 3]| p.iter().zip(q).all(|(a, b)| a.abs_diff(b) <= 1);
        assert!(near(srgb.pixel(16, 16).unwrap(), [51, 128, 204]));
        assert!(near(plain.pixel(0, 0).unwrap(), [128, 128, 128]));
    }

    #[test]
    fn rows_are_padded_to_256_bytes() {
        assert_eq!(padded_bytes_per_row(64), 256);
        assert_eq!(padded_bytes_per_row(65), 512);
        assert_eq!(padded_bytes_per_row(1), 256);
        assert_eq!(padded_bytes_per_row(100), 512);
    }
}
