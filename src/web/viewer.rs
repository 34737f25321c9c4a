//! The wgpu renderer behind the egui viewport: our WGSL pipelines (shaders/mesh.wgsl) drawn
//! through egui-wgpu paint callbacks into egui's render pass, which has a depth buffer.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use egui_wgpu::wgpu;
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

const POS_ATTR: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const NRM_ATTR: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Float32x3];
const SCALAR_ATTR: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![2 => Float32];

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24Plus;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Uniforms {
    pub view_proj: [[f32; 4]; 4],
    pub model: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub base_color: [f32; 4],
    pub scalar_range: [f32; 4],
    pub mode: [u32; 4],
}

/// Display-ready geometry of a snapshot. `generation` changes whenever the data does.
pub struct MeshData {
    pub generation: u64,
    pub positions: Vec<f32>,
    pub normals: Vec<f32>,
    pub triangles: Vec<u32>,
    pub edges: Vec<u32>,
}

/// Per-vertex scalars for the colour map; `generation` changes whenever the data does.
pub struct ScalarData {
    pub generation: u64,
    pub values: Vec<f32>,
}

/// A translucent overlay: a unit sphere or a unit disc (in the xy plane), placed by `model`.
#[derive(Clone, Copy, PartialEq)]
pub enum OverlayShape {
    Sphere,
    Disc,
}

#[derive(Clone, Copy)]
pub struct Overlay {
    pub shape: OverlayShape,
    pub model: Mat4,
    pub color: [f32; 4],
}

/// One frame's draw request, handed to egui as a paint callback.
pub struct ViewerFrame {
    pub mesh: Arc<MeshData>,
    pub scalars: Option<Arc<ScalarData>>,
    pub uniforms: Uniforms,
    pub edges: bool,
    pub overlay: Option<Overlay>,
}

struct GpuMesh {
    generation: u64,
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    triangles: wgpu::Buffer,
    triangle_count: u32,
    edges: wgpu::Buffer,
    edge_count: u32,
    vertex_count: usize,
}

struct GpuShape {
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    zeros: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// GPU state kept in egui-wgpu's callback resources.
pub struct ViewerResources {
    surface: wgpu::RenderPipeline,
    edges: wgpu::RenderPipeline,
    overlay: wgpu::RenderPipeline,
    surface_uniforms: wgpu::Buffer,
    surface_bind: wgpu::BindGroup,
    overlay_uniforms: wgpu::Buffer,
    overlay_bind: wgpu::BindGroup,
    mesh: Option<GpuMesh>,
    scalars: Option<(u64, wgpu::Buffer)>,
    zero_scalars: Option<(usize, wgpu::Buffer)>,
    sphere: GpuShape,
    disc: GpuShape,
    overlay_shape: Option<OverlayShape>,
}

impl ViewerResources {
    pub fn new(device: &wgpu::Device, target_format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/mesh.wgsl").into()),
        });
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewer uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewer"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let buf = |stride, attrs: &'static [wgpu::VertexAttribute]| {
            Some(wgpu::VertexBufferLayout { array_stride: stride, step_mode: wgpu::VertexStepMode::Vertex, attributes: attrs })
        };
        let (pos_attr, nrm_attr, scalar_attr) = (&POS_ATTR[..], &NRM_ATTR[..], &SCALAR_ATTR[..]);
        let surface_buffers = [buf(12, pos_attr), buf(12, nrm_attr), buf(4, scalar_attr)];
        let edge_buffers = [buf(12, pos_attr)];
        let depth = |write: bool| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            })
        };
        let pipeline = |label, vs, fs, buffers: &[Option<wgpu::VertexBufferLayout>], topology, write, blend| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState { topology, cull_mode: None, ..Default::default() },
                depth_stencil: depth(write),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: target_format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let surface = pipeline(
            "surface",
            "vs_surface",
            "fs_surface",
            &surface_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            true,
            None,
        );
        let edges = pipeline("edges", "vs_edges", "fs_edges", &edge_buffers, wgpu::PrimitiveTopology::LineList, false, None);
        let overlay = pipeline(
            "overlay",
            "vs_surface",
            "fs_overlay",
            &surface_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            false,
            Some(wgpu::BlendState::ALPHA_BLENDING),
        );
        let uniform_buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<Uniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let bind = |buffer: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &bind_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
            })
        };
        let surface_uniforms = uniform_buffer("surface uniforms");
        let overlay_uniforms = uniform_buffer("overlay uniforms");
        let surface_bind = bind(&surface_uniforms);
        let overlay_bind = bind(&overlay_uniforms);
        let (sp, sn, si) = unit_sphere(48, 24);
        let (dp, dn, di) = unit_disc(64);
        Self {
            surface,
            edges,
            overlay,
            surface_uniforms,
            surface_bind,
            overlay_uniforms,
            overlay_bind,
            mesh: None,
            scalars: None,
            zero_scalars: None,
            sphere: GpuShape::new(device, &sp, &sn, &si),
            disc: GpuShape::new(device, &dp, &dn, &di),
            overlay_shape: None,
        }
    }
}

impl GpuShape {
    fn new(device: &wgpu::Device, p: &[f32], n: &[f32], i: &[u32]) -> Self {
        Self {
            positions: init_buffer(device, p, wgpu::BufferUsages::VERTEX),
            normals: init_buffer(device, n, wgpu::BufferUsages::VERTEX),
            zeros: init_buffer(device, &vec![0f32; p.len() / 3], wgpu::BufferUsages::VERTEX),
            indices: init_buffer(device, i, wgpu::BufferUsages::INDEX),
            count: i.len() as u32,
        }
    }
}

fn init_buffer<T: Pod>(device: &wgpu::Device, data: &[T], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    // Zero-sized buffers are not allowed everywhere; keep at least one element's room.
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let padded;
    let contents = if bytes.is_empty() {
        padded = [0u8; 16];
        &padded[..]
    } else {
        bytes
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage })
}

impl egui_wgpu::CallbackTrait for ViewerFrame {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(r) = resources.get_mut::<ViewerResources>() else {
            return Vec::new();
        };
        if r.mesh.as_ref().map(|m| m.generation) != Some(self.mesh.generation) {
            let m = &self.mesh;
            r.mesh = Some(GpuMesh {
                generation: m.generation,
                positions: init_buffer(device, &m.positions, wgpu::BufferUsages::VERTEX),
                normals: init_buffer(device, &m.normals, wgpu::BufferUsages::VERTEX),
                triangles: init_buffer(device, &m.triangles, wgpu::BufferUsages::INDEX),
                triangle_count: m.triangles.len() as u32,
                edges: init_buffer(device, &m.edges, wgpu::BufferUsages::INDEX),
                edge_count: m.edges.len() as u32,
                vertex_count: m.positions.len() / 3,
            });
        }
        let n = r.mesh.as_ref().map_or(0, |m| m.vertex_count);
        match &self.scalars {
            Some(s) if s.values.len() == n => {
                if r.scalars.as_ref().map(|x| x.0) != Some(s.generation) {
                    r.scalars = Some((s.generation, init_buffer(device, &s.values, wgpu::BufferUsages::VERTEX)));
                }
            }
            _ => r.scalars = None,
        }
        if r.zero_scalars.as_ref().map(|z| z.0) != Some(n) {
            r.zero_scalars = Some((n, init_buffer(device, &vec![0f32; n.max(1)], wgpu::BufferUsages::VERTEX)));
        }
        queue.write_buffer(&r.surface_uniforms, 0, bytemuck::bytes_of(&self.uniforms));
        r.overlay_shape = self.overlay.map(|o| o.shape);
        if let Some(o) = self.overlay {
            let mut u = self.uniforms;
            u.model = o.model.to_cols_array_2d();
            u.base_color = o.color;
            u.mode[1] = 0;
            queue.write_buffer(&r.overlay_uniforms, 0, bytemuck::bytes_of(&u));
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        let Some(r) = resources.get::<ViewerResources>() else { return };
        let Some(m) = &r.mesh else { return };
        let scalars = match (&r.scalars, &r.zero_scalars) {
            (Some((_, b)), _) => b,
            (None, Some((_, b))) => b,
            (None, None) => return,
        };
        pass.set_bind_group(0, &r.surface_bind, &[]);
        if m.triangle_count > 0 {
            pass.set_pipeline(&r.surface);
            pass.set_vertex_buffer(0, m.positions.slice(..));
            pass.set_vertex_buffer(1, m.normals.slice(..));
            pass.set_vertex_buffer(2, scalars.slice(..));
            pass.set_index_buffer(m.triangles.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..m.triangle_count, 0, 0..1);
        }
        if self.edges && m.edge_count > 0 {
            pass.set_pipeline(&r.edges);
            pass.set_vertex_buffer(0, m.positions.slice(..));
            pass.set_index_buffer(m.edges.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..m.edge_count, 0, 0..1);
        }
        if let Some(shape) = r.overlay_shape {
            let s = if shape == OverlayShape::Sphere { &r.sphere } else { &r.disc };
            pass.set_pipeline(&r.overlay);
            pass.set_bind_group(0, &r.overlay_bind, &[]);
            pass.set_vertex_buffer(0, s.positions.slice(..));
            pass.set_vertex_buffer(1, s.normals.slice(..));
            pass.set_vertex_buffer(2, s.zeros.slice(..));
            pass.set_index_buffer(s.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..s.count, 0, 0..1);
        }
    }
}

/// Unit sphere: positions equal normals.
fn unit_sphere(slices: u32, stacks: u32) -> (Vec<f32>, Vec<f32>, Vec<u32>) {
    let mut p = Vec::new();
    let mut idx = Vec::new();
    for j in 0..=stacks {
        let theta = std::f32::consts::PI * j as f32 / stacks as f32;
        for i in 0..=slices {
            let phi = std::f32::consts::TAU * i as f32 / slices as f32;
            p.extend_from_slice(&[theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]);
        }
    }
    let w = slices + 1;
    for j in 0..stacks {
        for i in 0..slices {
            let a = j * w + i;
            idx.extend_from_slice(&[a, a + w, a + 1, a + 1, a + w, a + w + 1]);
        }
    }
    (p.clone(), p, idx)
}

/// Unit disc in the xy plane with normal +z.
fn unit_disc(segments: u32) -> (Vec<f32>, Vec<f32>, Vec<u32>) {
    let mut p = vec![0.0, 0.0, 0.0];
    let mut idx = Vec::new();
    for i in 0..segments {
        let a = std::f32::consts::TAU * i as f32 / segments as f32;
        p.extend_from_slice(&[a.cos(), a.sin(), 0.0]);
        idx.extend_from_slice(&[0, 1 + i, 1 + (i + 1) % segments]);
    }
    let n = (0..=segments).flat_map(|_| [0.0, 0.0, 1.0]).collect();
    (p, n, idx)
}

/// Orbit camera around a target, z up (angles in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
    pub target: Vec3,
    /// Radius of the scene, for clip planes.
    pub scene_radius: f32,
}

impl OrbitCamera {
    pub const FOV_Y: f32 = 0.7;

    pub fn framing(center: Vec3, radius: f32) -> Self {
        let radius = radius.max(1e-6);
        Self {
            yaw: -0.9,
            pitch: 0.55,
            distance: radius / (Self::FOV_Y * 0.5).tan() * 1.15,
            target: center,
            scene_radius: radius,
        }
    }

    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * cy, cp * sy, sp)
    }

    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Z)
    }

    pub fn proj(&self, aspect: f32) -> Mat4 {
        let far = self.distance + 4.0 * self.scene_radius;
        let near = (self.distance - 4.0 * self.scene_radius).max(far * 1e-4);
        Mat4::perspective_rh(Self::FOV_Y, aspect.max(1e-3), near, far)
    }

    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.55, 1.55);
    }

    /// Pans by a screen-space drag of (dx, dy) points in a viewport `height` points tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let scale = 2.0 * self.distance * (Self::FOV_Y * 0.5).tan() / height.max(1.0);
        let view = self.view();
        let right = Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let up = Vec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
        self.target += (-dx * right + dy * up) * scale;
    }

    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance / factor.max(1e-3)).clamp(self.scene_radius * 1e-3, self.scene_radius * 1e3);
    }

    /// World-space ray through a point given in normalized device coordinates.
    pub fn ray(&self, ndc_x: f32, ndc_y: f32, aspect: f32) -> (Vec3, Vec3) {
        let inv = (self.proj(aspect) * self.view()).inverse();
        let a = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
        let b = inv.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
        (a, (b - a).normalize())
    }
}
