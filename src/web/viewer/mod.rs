//! The wgpu renderer behind the egui viewport: our WGSL pipelines (shaders/mesh.wgsl) drawn
//! through egui-wgpu paint callbacks into egui's render pass, which has a depth buffer. The
//! camera ([`camera`]) and picking ([`picking`]) stand apart from the GPU code.

pub mod camera;
pub mod picking;

use std::collections::HashMap;
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
#[derive(Default)]
pub struct MeshData {
    pub generation: u64,
    pub positions: Vec<f32>,
    pub normals: Vec<f32>,
    pub triangles: Vec<u32>,
    /// Line segments (pairs of vertex indices).
    pub edges: Vec<u32>,
}

/// Per-vertex scalars for the colour map; `generation` changes whenever the data does.
pub struct ScalarData {
    pub generation: u64,
    pub values: Vec<f32>,
}

/// What a layer draws.
#[derive(Clone)]
pub enum Geometry {
    Mesh(Arc<MeshData>),
    /// The unit sphere (for central spheres and Ω).
    UnitSphere,
    /// The unit disc in the xy plane, normal +z (for planes).
    UnitDisc,
}

/// A colour map over per-vertex scalars: data, display range, diverging or sequential.
#[derive(Clone)]
pub struct ColorMap {
    pub scalars: Arc<ScalarData>,
    pub range: (f32, f32),
    pub diverging: bool,
}

/// How a layer is drawn.
#[derive(Clone)]
pub enum Style {
    /// Opaque shaded triangles; `shading` 0 flat, 1 smooth, 2 reflective.
    Surface { shading: u32, color: [f32; 4], color_map: Option<ColorMap> },
    /// The geometry's line segments.
    Lines { color: [f32; 4] },
    /// Alpha-blended triangles, not writing depth.
    Translucent { color: [f32; 4] },
}

#[derive(Clone)]
pub struct Layer {
    pub geometry: Geometry,
    pub model: Mat4,
    pub style: Style,
}

/// One frame's draw request, handed to egui as a paint callback. Layers draw in order.
pub struct ViewerFrame {
    pub view_proj: Mat4,
    pub eye: Vec3,
    /// World distance lines are pulled toward the eye.
    pub line_bias: f32,
    pub layers: Vec<Layer>,
}

/// Layers beyond this are not drawn (one uniform slot each).
pub const MAX_LAYERS: usize = 32;
/// Uniform slots are spaced by the largest minUniformBufferOffsetAlignment WebGPU allows.
const SLOT: u64 = 256;

struct GpuMesh {
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    zeros: wgpu::Buffer,
    triangles: wgpu::Buffer,
    triangle_count: u32,
    edges: wgpu::Buffer,
    edge_count: u32,
}

impl GpuMesh {
    fn new(device: &wgpu::Device, p: &[f32], n: &[f32], t: &[u32], e: &[u32]) -> Self {
        let normals = if n.len() == p.len() { n.to_vec() } else { vec![0.0; p.len()] };
        Self {
            positions: init_buffer(device, p, wgpu::BufferUsages::VERTEX),
            normals: init_buffer(device, &normals, wgpu::BufferUsages::VERTEX),
            zeros: init_buffer(device, &vec![0f32; p.len() / 3], wgpu::BufferUsages::VERTEX),
            triangles: init_buffer(device, t, wgpu::BufferUsages::INDEX),
            triangle_count: t.len() as u32,
            edges: init_buffer(device, e, wgpu::BufferUsages::INDEX),
            edge_count: e.len() as u32,
        }
    }
}

/// GPU state kept in egui-wgpu's callback resources.
pub struct ViewerResources {
    surface: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    translucent: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind: wgpu::BindGroup,
    meshes: HashMap<u64, GpuMesh>,
    scalars: HashMap<u64, wgpu::Buffer>,
    sphere: GpuMesh,
    disc: GpuMesh,
    /// What `paint` draws: (geometry key, scalar key, style kind) per layer.
    draws: Vec<Draw>,
}

#[derive(Clone, Copy)]
enum Key {
    Mesh(u64),
    Sphere,
    Disc,
}

#[derive(Clone, Copy)]
enum Kind {
    Surface,
    Lines,
    Translucent,
}

#[derive(Clone, Copy)]
struct Draw {
    geometry: Key,
    scalars: Option<u64>,
    kind: Kind,
}

impl ViewerResources {
    pub fn new(device: &wgpu::Device, target_format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/mesh.wgsl").into()),
        });
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewer uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: std::num::NonZeroU64::new(std::mem::size_of::<Uniforms>() as u64),
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
        let surface_buffers = [buf(12, &POS_ATTR), buf(12, &NRM_ATTR), buf(4, &SCALAR_ATTR)];
        let line_buffers = [buf(12, &POS_ATTR)];
        let pipeline = |label, vs, fs, buffers: &[Option<wgpu::VertexBufferLayout>], topology, write, blend| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState { module: &shader, entry_point: Some(vs), compilation_options: Default::default(), buffers },
                primitive: wgpu::PrimitiveState { topology, cull_mode: None, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(write),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState { format: target_format, blend, write_mask: wgpu::ColorWrites::ALL })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let tri = wgpu::PrimitiveTopology::TriangleList;
        let surface = pipeline("surface", "vs_surface", "fs_surface", &surface_buffers, tri, true, None);
        let lines = pipeline("lines", "vs_edges", "fs_edges", &line_buffers, wgpu::PrimitiveTopology::LineList, true, None);
        let translucent = pipeline("translucent", "vs_surface", "fs_overlay", &surface_buffers, tri, false, Some(wgpu::BlendState::ALPHA_BLENDING));
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("layer uniforms"),
            size: SLOT * MAX_LAYERS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &bind_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &uniforms,
                    offset: 0,
                    size: std::num::NonZeroU64::new(std::mem::size_of::<Uniforms>() as u64),
                }),
            }],
        });
        let (sp, sn, si) = unit_sphere(48, 24);
        let (dp, dn, di) = unit_disc(64);
        Self {
            surface,
            lines,
            translucent,
            uniforms,
            bind,
            meshes: HashMap::new(),
            scalars: HashMap::new(),
            sphere: GpuMesh::new(device, &sp, &sn, &si, &[]),
            disc: GpuMesh::new(device, &dp, &dn, &di, &[]),
            draws: Vec::new(),
        }
    }

    fn gpu_mesh(&self, key: Key) -> Option<&GpuMesh> {
        match key {
            Key::Mesh(g) => self.meshes.get(&g),
            Key::Sphere => Some(&self.sphere),
            Key::Disc => Some(&self.disc),
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
        r.draws.clear();
        let mut used_meshes = Vec::new();
        let mut used_scalars = Vec::new();
        for (slot, layer) in self.layers.iter().take(MAX_LAYERS).enumerate() {
            let (key, vertex_count) = match &layer.geometry {
                Geometry::Mesh(m) => {
                    r.meshes.entry(m.generation).or_insert_with(|| GpuMesh::new(device, &m.positions, &m.normals, &m.triangles, &m.edges));
                    used_meshes.push(m.generation);
                    (Key::Mesh(m.generation), m.positions.len() / 3)
                }
                Geometry::UnitSphere => (Key::Sphere, 0),
                Geometry::UnitDisc => (Key::Disc, 0),
            };
            let mut u = Uniforms {
                view_proj: self.view_proj.to_cols_array_2d(),
                model: layer.model.to_cols_array_2d(),
                eye: [self.eye.x, self.eye.y, self.eye.z, 1.0],
                base_color: [1.0; 4],
                scalar_range: [0.0, 1.0, 0.0, 0.0],
                mode: [1, 0, 0, 0],
            };
            let mut scalars = None;
            let kind = match &layer.style {
                Style::Surface { shading, color, color_map } => {
                    u.mode[0] = *shading;
                    u.base_color = *color;
                    if let Some(cm) = color_map.as_ref().filter(|cm| cm.scalars.values.len() == vertex_count) {
                        let g = cm.scalars.generation;
                        r.scalars.entry(g).or_insert_with(|| init_buffer(device, &cm.scalars.values, wgpu::BufferUsages::VERTEX));
                        used_scalars.push(g);
                        scalars = Some(g);
                        u.mode[1] = 1;
                        u.scalar_range = [cm.range.0, cm.range.1, cm.diverging as u32 as f32, 0.0];
                    }
                    Kind::Surface
                }
                Style::Lines { color } => {
                    u.base_color = *color;
                    u.scalar_range[3] = self.line_bias;
                    Kind::Lines
                }
                Style::Translucent { color } => {
                    u.base_color = *color;
                    Kind::Translucent
                }
            };
            queue.write_buffer(&r.uniforms, slot as u64 * SLOT, bytemuck::bytes_of(&u));
            r.draws.push(Draw { geometry: key, scalars, kind });
        }
        // Keep GPU buffers only for what is still shown.
        r.meshes.retain(|g, _| used_meshes.contains(g));
        r.scalars.retain(|g, _| used_scalars.contains(g));
        Vec::new()
    }

    fn paint(&self, _info: egui::PaintCallbackInfo, pass: &mut wgpu::RenderPass<'static>, resources: &egui_wgpu::CallbackResources) {
        let Some(r) = resources.get::<ViewerResources>() else { return };
        for (slot, d) in r.draws.iter().enumerate() {
            let Some(m) = r.gpu_mesh(d.geometry) else { continue };
            pass.set_bind_group(0, &r.bind, &[(slot as u64 * SLOT) as u32]);
            match d.kind {
                Kind::Surface | Kind::Translucent => {
                    if m.triangle_count == 0 {
                        continue;
                    }
                    let scalars = d.scalars.and_then(|g| r.scalars.get(&g)).unwrap_or(&m.zeros);
                    pass.set_pipeline(if matches!(d.kind, Kind::Surface) { &r.surface } else { &r.translucent });
                    pass.set_vertex_buffer(0, m.positions.slice(..));
                    pass.set_vertex_buffer(1, m.normals.slice(..));
                    pass.set_vertex_buffer(2, scalars.slice(..));
                    pass.set_index_buffer(m.triangles.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..m.triangle_count, 0, 0..1);
                }
                Kind::Lines => {
                    if m.edge_count == 0 {
                        continue;
                    }
                    pass.set_pipeline(&r.lines);
                    pass.set_vertex_buffer(0, m.positions.slice(..));
                    pass.set_index_buffer(m.edges.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..m.edge_count, 0, 0..1);
                }
            }
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
