//! glTF 2.0: `.gltf` JSON with embedded `data:` buffers, and binary `.glb`.
//!
//! The JSON is deserialized with `gltf::json`; everything after that (index checks, node
//! hierarchy, accessor decoding) is done here with checked arithmetic, because the `gltf`
//! crate's own validation and readers can panic on hostile input. All meshes instanced by the
//! default scene (or scene 0; or every mesh once if there are no scenes) are merged, with node
//! transforms accumulated in f64.

use super::base64;
use super::raw::{Ctx, ImportError, RawMesh, MAX_TRIANGLES, MAX_VERTICES};
use ::gltf::json;
use glam::{DMat4, DQuat, DVec3};
use json::accessor::{ComponentType, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use std::borrow::Cow;

const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Parses a binary glTF (GLB) container.
pub(super) fn parse_glb(bytes: &[u8], ctx: &Ctx) -> Result<RawMesh, ImportError> {
    if !bytes.starts_with(b"glTF") {
        return Err(ctx.malformed(None, "not a GLB file (it does not start with 'glTF'); export as binary glTF 2.0 (.glb)"));
    }
    let (Some(version), Some(length)) = (u32_at(bytes, 4), u32_at(bytes, 8)) else {
        return Err(ctx.malformed(None, format!("truncated GLB (file has {} bytes, the header alone needs 12)", bytes.len())));
    };
    if version != 2 {
        return Err(ctx.unsupported(format!("GLB version {version} is not supported; re-export as glTF 2.0")));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(ctx.malformed(None, format!("truncated GLB (header says {length} bytes, file has {})", bytes.len())));
    }
    if length < 12 {
        return Err(ctx.malformed(None, format!("invalid GLB header: total length {length} is below 12")));
    }
    let data = &bytes[12..length];
    let (mut json_chunk, mut bin_chunk): (Option<&[u8]>, Option<&[u8]>) = (None, None);
    let mut pos = 0usize;
    let mut index = 0usize;
    while pos < data.len() {
        let (Some(len), Some(ty)) = (u32_at(data, pos), u32_at(data, pos + 4)) else {
            return Err(ctx.malformed(None, format!("truncated GLB: chunk header at byte {} is cut off", 12 + pos)));
        };
        let start = pos + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= data.len()).ok_or_else(|| {
            ctx.malformed(None, format!("truncated GLB: chunk {index} declares {len} bytes but only {} remain", data.len() - start))
        })?;
        let chunk = &data[start..end];
        match ty {
            CHUNK_JSON if index == 0 => json_chunk = Some(chunk),
            CHUNK_BIN if index > 0 && bin_chunk.is_none() => bin_chunk = Some(chunk),
            _ if index == 0 => return Err(ctx.malformed(None, "invalid GLB: the first chunk must be the JSON chunk")),
            _ => {}
        }
        pos = end;
        index += 1;
    }
    let json_chunk = json_chunk.ok_or_else(|| ctx.malformed(None, "invalid GLB: no JSON chunk"))?;
    // Padding is spaces per the spec; tolerate NUL padding too.
    let json_chunk = trim_end_padding(json_chunk);
    parse_document(json_chunk, bin_chunk, true, ctx)
}

/// Parses a `.gltf` JSON file.
pub(super) fn parse_gltf(bytes: &[u8], ctx: &Ctx) -> Result<RawMesh, ImportError> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    parse_document(trim_end_padding(text), None, false, ctx)
}

fn trim_end_padding(b: &[u8]) -> &[u8] {
    let end = b.iter().rposition(|&c| !(c == 0 || c.is_ascii_whitespace())).map_or(0, |i| i + 1);
    &b[..end]
}

fn json_error(e: serde_json::Error, text: &[u8], is_glb: bool, ctx: &Ctx) -> ImportError {
    // glTF 1.0 has a different schema: say so instead of reporting a schema mismatch.
    if let Ok(v) = serde_json::from_slice::<serde_json::Value>(text) {
        let version = v.get("asset").and_then(|a| a.get("version")).and_then(|v| v.as_str());
        if let Some(ver) = version.filter(|s| !s.starts_with('2')) {
            return ctx.unsupported(format!("glTF version {ver} is not supported; re-export as glTF 2.0"));
        }
    }
    let full = e.to_string();
    let msg = match full.rfind(" at line ") {
        Some(i) if e.line() > 0 => &full[..i],
        _ => full.as_str(),
    };
    if is_glb || e.line() == 0 {
        let loc = if e.line() > 0 { format!(" (JSON chunk line {}, column {})", e.line(), e.column()) } else { String::new() };
        ctx.malformed(None, format!("invalid glTF JSON{loc}: {msg}"))
    } else {
        ctx.malformed(Some(e.line()), format!("invalid glTF JSON (column {}): {msg}", e.column()))
    }
}

/// Decoded buffers, loaded on first use.
struct Buffers<'a> {
    data: Vec<Option<Cow<'a, [u8]>>>,
    bin: Option<&'a [u8]>,
}

impl<'a> Buffers<'a> {
    fn ensure(&mut self, root: &json::Root, i: usize, ctx: &Ctx) -> Result<(), ImportError> {
        if self.data.get(i).is_some_and(|d| d.is_some()) {
            return Ok(());
        }
        let b = root.buffers.get(i).ok_or_else(|| ctx.malformed(None, format!("buffer {i} does not exist ({} buffers)", root.buffers.len())))?;
        let bytes: Cow<'a, [u8]> = match &b.uri {
            None => match self.bin {
                Some(bin) if i == 0 => Cow::Borrowed(bin),
                _ => return Err(ctx.malformed(None, format!("buffer {i} has no uri and there is no GLB binary chunk for it"))),
            },
            Some(uri) if uri.get(..5).is_some_and(|p| p.eq_ignore_ascii_case("data:")) => {
                let comma = uri.find(',').ok_or_else(|| ctx.malformed(None, format!("buffer {i} has a malformed data: URI (no comma)")))?;
                let header = &uri[5..comma];
                if !header.to_ascii_lowercase().ends_with(";base64") {
                    return Err(ctx.unsupported(format!(
                        "buffer {i} uses a data: URI that is not base64-encoded; re-export with embedded base64 buffers or as .glb"
                    )));
                }
                let decoded =
                    base64::decode(&uri.as_bytes()[comma + 1..]).map_err(|e| ctx.malformed(None, format!("buffer {i}: {e} in its data: URI")))?;
                Cow::Owned(decoded)
            }
            Some(uri) => {
                let shown: String = uri.chars().take(80).collect();
                return Err(ctx.unsupported(format!("buffer {i} uses external file '{shown}'; embed it as a data: URI or export as .glb")));
            }
        };
        let declared = b.byte_length.0;
        if (bytes.len() as u64) < declared {
            return Err(ctx.malformed(None, format!("buffer {i} declares {declared} bytes but contains only {}", bytes.len())));
        }
        if self.data.len() <= i {
            self.data.resize(i + 1, None);
        }
        self.data[i] = Some(bytes);
        Ok(())
    }

    fn get(&self, i: usize) -> &[u8] {
        self.data.get(i).and_then(|d| d.as_deref()).unwrap_or(&[])
    }

    /// Loads every buffer accessor `ai` reads from.
    fn ensure_for_accessor(&mut self, root: &json::Root, ai: usize, ctx: &Ctx) -> Result<(), ImportError> {
        let acc = accessor(root, ai, ctx)?;
        let mut views = Vec::with_capacity(3);
        views.extend(acc.buffer_view.map(|v| v.value()));
        if let Some(s) = &acc.sparse {
            views.push(s.indices.buffer_view.value());
            views.push(s.values.buffer_view.value());
        }
        for v in views {
            let buffer = view(root, v, ctx)?.buffer.value();
            self.ensure(root, buffer, ctx)?;
        }
        Ok(())
    }
}

fn accessor<'r>(root: &'r json::Root, ai: usize, ctx: &Ctx) -> Result<&'r json::Accessor, ImportError> {
    root.accessors.get(ai).ok_or_else(|| ctx.malformed(None, format!("accessor {ai} does not exist ({} accessors)", root.accessors.len())))
}

fn view<'r>(root: &'r json::Root, vi: usize, ctx: &Ctx) -> Result<&'r json::buffer::View, ImportError> {
    root.buffer_views.get(vi).ok_or_else(|| ctx.malformed(None, format!("bufferView {vi} does not exist ({} bufferViews)", root.buffer_views.len())))
}

fn component_size(ct: ComponentType) -> u64 {
    match ct {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// One component at `at`, as f64 (normalized integers mapped to [-1, 1] / [0, 1]).
fn read_component(data: &[u8], at: u64, ct: ComponentType, normalized: bool) -> Option<f64> {
    let at = usize::try_from(at).ok()?;
    let b = data.get(at..at.checked_add(component_size(ct) as usize)?)?;
    let (v, scale) = match ct {
        ComponentType::I8 => (f64::from(b[0] as i8), 127.0),
        ComponentType::U8 => (f64::from(b[0]), 255.0),
        ComponentType::I16 => (f64::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
        ComponentType::U16 => (f64::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
        ComponentType::U32 => (f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])), 4294967295.0),
        ComponentType::F32 => return Some(f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))),
    };
    Some(if normalized { (v / scale).max(-1.0) } else { v })
}

/// Byte range `[start, end)` of a buffer view inside its (loaded) buffer.
fn view_range(root: &json::Root, bufs: &Buffers, vi: usize, ctx: &Ctx) -> Result<(u64, u64, usize), ImportError> {
    let v = view(root, vi, ctx)?;
    let b = v.buffer.value();
    let start = v.byte_offset.map_or(0, |o| o.0);
    let end = start.checked_add(v.byte_length.0);
    let len = bufs.get(b).len() as u64;
    match end {
        Some(end) if end <= len => Ok((start, end, b)),
        _ => Err(ctx.malformed(None, format!("bufferView {vi} (offset {start}, length {}) lies outside buffer {b} ({len} bytes)", v.byte_length.0))),
    }
}

/// Decoded accessor: `count * dims` values, row by row.
struct AccessorData {
    dims: usize,
    values: Vec<f64>,
}

/// Reads accessor `ai` (scalar or vector, any component type) with full bounds checks.
/// `max_count` bounds the allocation; callers pass limits already checked against the file.
fn read_accessor(root: &json::Root, bufs: &Buffers, ai: usize, max_count: u64, ctx: &Ctx) -> Result<AccessorData, ImportError> {
    let acc = accessor(root, ai, ctx)?;
    let ct = match acc.component_type {
        Checked::Valid(g) => g.0,
        Checked::Invalid => return Err(ctx.malformed(None, format!("accessor {ai} has an invalid componentType"))),
    };
    let dims: usize = match acc.type_ {
        Checked::Valid(Type::Scalar) => 1,
        Checked::Valid(Type::Vec2) => 2,
        Checked::Valid(Type::Vec3) => 3,
        Checked::Valid(Type::Vec4) => 4,
        Checked::Valid(_) => return Err(ctx.malformed(None, format!("accessor {ai} is a matrix; expected positions or indices"))),
        Checked::Invalid => return Err(ctx.malformed(None, format!("accessor {ai} has an invalid type"))),
    };
    let count = acc.count.0;
    if count > max_count {
        return Err(ctx.too_large("accessor elements", count, max_count as usize));
    }
    let csize = component_size(ct);
    let elem = csize * dims as u64;
    let mut values = Vec::new();
    let out_of_range = |what: String| ctx.malformed(None, what);

    if let Some(vi) = acc.buffer_view {
        let vi = vi.value();
        let (vstart, vend, b) = view_range(root, bufs, vi, ctx)?;
        let data = bufs.get(b);
        let stride = match view(root, vi, ctx)?.byte_stride {
            Some(s) => s.0 as u64,
            None => elem,
        };
        if stride < elem {
            return Err(out_of_range(format!("accessor {ai}: byteStride {stride} is smaller than one element ({elem} bytes)")));
        }
        let offset = acc.byte_offset.map_or(0, |o| o.0);
        if count > 0 {
            let need = stride.checked_mul(count - 1).and_then(|x| x.checked_add(elem)).and_then(|x| x.checked_add(offset));
            match need {
                Some(need) if need <= vend - vstart => {}
                _ => {
                    return Err(out_of_range(format!(
                    "accessor {ai} ({count} elements of {elem} bytes, stride {stride}, offset {offset}) does not fit in bufferView {vi} ({} bytes)",
                    vend - vstart
                )))
                }
            }
        }
        // In range: count * elem <= view length <= buffer length, so this allocation is backed by data.
        values.reserve_exact(count as usize * dims);
        let base = vstart.saturating_add(offset);
        for i in 0..count {
            let at = base + i * stride;
            for c in 0..dims as u64 {
                let v = read_component(data, at + c * csize, ct, acc.normalized)
                    .ok_or_else(|| out_of_range(format!("accessor {ai}: read past the end of buffer {b}")))?;
                values.push(v);
            }
        }
    } else {
        // No bufferView: zeros, overwritten by sparse entries. Such an accessor is backed by no
        // data, so a tiny file could declare millions of elements: only as many as the sparse
        // entries (the data that is there) are accepted.
        let backed = acc.sparse.as_ref().map_or(0, |s| s.count.0);
        if count > backed.max(3) {
            return Err(ctx.unsupported(format!(
                "accessor {ai} declares {count} elements but has no bufferView (only {backed} sparse entries carry data): \
                 accessors of zeros are not supported"
            )));
        }
        values.resize(count as usize * dims, 0.0);
    }

    if let Some(sparse) = &acc.sparse {
        let sc = sparse.count.0;
        if sc > count {
            return Err(out_of_range(format!("accessor {ai}: sparse count {sc} exceeds the accessor count {count}")));
        }
        let ict = match sparse.indices.component_type {
            Checked::Valid(t) => t.0,
            Checked::Invalid => return Err(out_of_range(format!("accessor {ai}: invalid sparse index componentType"))),
        };
        let isize = component_size(ict);
        let (istart, iend, ib) = view_range(root, bufs, sparse.indices.buffer_view.value(), ctx)?;
        let (vstart, vend, vb) = view_range(root, bufs, sparse.values.buffer_view.value(), ctx)?;
        let ioff = istart.checked_add(sparse.indices.byte_offset.0);
        let voff = vstart.checked_add(sparse.values.byte_offset.0);
        let ifits = ioff.and_then(|o| o.checked_add(sc.checked_mul(isize)?)).is_some_and(|e| e <= iend);
        let vfits = voff.and_then(|o| o.checked_add(sc.checked_mul(elem)?)).is_some_and(|e| e <= vend);
        let (Some(ioff), Some(voff), true, true) = (ioff, voff, ifits, vfits) else {
            return Err(out_of_range(format!("accessor {ai}: sparse data does not fit in its bufferViews")));
        };
        let (idata, vdata) = (bufs.get(ib), bufs.get(vb));
        for k in 0..sc {
            let bad = || out_of_range(format!("accessor {ai}: invalid sparse entry {k}"));
            let target = read_component(idata, ioff + k * isize, ict, false).ok_or_else(bad)?;
            if target >= count as f64 {
                return Err(out_of_range(format!("accessor {ai}: sparse index {target} is out of range ({count} elements)")));
            }
            let row = target as usize * dims;
            for c in 0..dims {
                let v = read_component(vdata, voff + k * elem + c as u64 * csize, ct, acc.normalized).ok_or_else(bad)?;
                if let Some(slot) = values.get_mut(row + c) {
                    *slot = v;
                }
            }
        }
    }
    Ok(AccessorData { dims, values })
}

/// Local transform of node `ni` in f64: its matrix, or translation * rotation * scale.
fn node_matrix(node: &json::Node, ni: usize, ctx: &Ctx) -> Result<DMat4, ImportError> {
    let m = if let Some(m) = node.matrix {
        DMat4::from_cols_array(&m.map(f64::from))
    } else {
        let t = node.translation.map_or(DVec3::ZERO, |t| DVec3::from_array(t.map(f64::from)));
        let s = node.scale.map_or(DVec3::ONE, |s| DVec3::from_array(s.map(f64::from)));
        let r = match node.rotation {
            Some(q) => {
                let q = DQuat::from_array(q.0.map(f64::from));
                let len = q.length();
                if !(len.is_finite() && len > 0.0) {
                    return Err(ctx.malformed(None, format!("node {ni} has an invalid rotation quaternion")));
                }
                q / len
            }
            None => DQuat::IDENTITY,
        };
        DMat4::from_scale_rotation_translation(s, r, t)
    };
    if !m.is_finite() {
        return Err(ctx.malformed(None, format!("node {ni} has a non-finite transform")));
    }
    Ok(m)
}

/// (mesh index, world transform) for every mesh instance to import.
fn instances(root: &json::Root, notes: &mut Vec<String>, ctx: &Ctx) -> Result<Vec<(usize, DMat4)>, ImportError> {
    if root.scenes.is_empty() {
        if !root.meshes.is_empty() {
            notes.push("the file has no scene; imported every mesh once, untransformed".into());
        }
        return Ok((0..root.meshes.len()).map(|m| (m, DMat4::IDENTITY)).collect());
    }
    let si = root.scene.map_or(0, |s| s.value());
    let scene =
        root.scenes.get(si).ok_or_else(|| ctx.malformed(None, format!("default scene {si} does not exist ({} scenes)", root.scenes.len())))?;
    let mut visited = vec![false; root.nodes.len()];
    let mut repeated = 0usize;
    let mut out = Vec::new();
    let mut stack: Vec<(usize, DMat4)> = scene.nodes.iter().rev().map(|n| (n.value(), DMat4::IDENTITY)).collect();
    while let Some((ni, parent)) = stack.pop() {
        let node = root.nodes.get(ni).ok_or_else(|| ctx.malformed(None, format!("node {ni} does not exist ({} nodes)", root.nodes.len())))?;
        if std::mem::replace(&mut visited[ni], true) {
            repeated += 1;
            continue;
        }
        let world = parent * node_matrix(node, ni, ctx)?;
        if let Some(m) = node.mesh {
            let m = m.value();
            if m >= root.meshes.len() {
                return Err(ctx.malformed(None, format!("node {ni} refers to mesh {m}, which does not exist ({} meshes)", root.meshes.len())));
            }
            out.push((m, world));
        }
        if let Some(children) = &node.children {
            stack.extend(children.iter().rev().map(|c| (c.value(), world)));
        }
    }
    if repeated > 0 {
        notes.push(format!("ignored {repeated} repeated node references (the node hierarchy must be a tree)"));
    }
    Ok(out)
}

fn is_triangle_mode(mode: Mode) -> bool {
    matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
}

fn triangles_for(mode: Mode, n: u64) -> u64 {
    match mode {
        Mode::Triangles => n / 3,
        Mode::TriangleStrip | Mode::TriangleFan => n.saturating_sub(2),
        _ => 0,
    }
}

fn parse_document(text: &[u8], bin: Option<&[u8]>, is_glb: bool, ctx: &Ctx) -> Result<RawMesh, ImportError> {
    let root: json::Root = serde_json::from_slice(text).map_err(|e| json_error(e, text, is_glb, ctx))?;
    if !root.asset.version.starts_with('2') {
        return Err(ctx.unsupported(format!("glTF version {} is not supported; re-export as glTF 2.0", root.asset.version)));
    }
    let mut raw = RawMesh::default();
    for ext in &root.extensions_required {
        match ext.as_str() {
            "KHR_draco_mesh_compression" | "EXT_meshopt_compression" => {
                return Err(ctx.unsupported(format!("the file requires {ext}, which is not supported; re-export without mesh compression")))
            }
            "KHR_mesh_quantization" => {}
            other => raw.notes.push(format!("ignored required extension {other}")),
        }
    }
    let instances = instances(&root, &mut raw.notes, ctx)?;

    // Limits first, from declared counts, before reading anything.
    let pos_key = Checked::Valid(Semantic::Positions);
    let (mut total_tris, mut total_verts) = (0u64, 0u64);
    for &(m, _) in &instances {
        for p in &root.meshes[m].primitives {
            let (Checked::Valid(mode), Some(pa)) = (p.mode, p.attributes.get(&pos_key)) else {
                continue;
            };
            if !is_triangle_mode(mode) {
                continue;
            }
            let nv = accessor(&root, pa.value(), ctx)?.count.0;
            let ni = match p.indices {
                Some(ia) => accessor(&root, ia.value(), ctx)?.count.0,
                None => nv,
            };
            total_tris = total_tris.saturating_add(triangles_for(mode, ni));
            total_verts = total_verts.saturating_add(nv);
        }
    }
    ctx.check_limits(total_tris, total_verts)?;

    let mut bufs = Buffers { data: Vec::new(), bin };
    let (mut points, mut lines, mut unknown_mode, mut no_position, mut leftover) = (0, 0, 0, 0, 0);
    for &(m, world) in &instances {
        let flip = world.determinant() < 0.0;
        for (pi, p) in root.meshes[m].primitives.iter().enumerate() {
            let mode = match p.mode {
                Checked::Valid(Mode::Points) => {
                    points += 1;
                    continue;
                }
                Checked::Valid(Mode::Lines | Mode::LineLoop | Mode::LineStrip) => {
                    lines += 1;
                    continue;
                }
                Checked::Valid(mode) => mode,
                Checked::Invalid => {
                    unknown_mode += 1;
                    continue;
                }
            };
            let Some(pa) = p.attributes.get(&pos_key) else {
                no_position += 1;
                continue;
            };
            let pa = pa.value();
            bufs.ensure_for_accessor(&root, pa, ctx)?;
            let pos = read_accessor(&root, &bufs, pa, MAX_VERTICES as u64, ctx)?;
            if pos.dims != 3 {
                return Err(ctx.malformed(None, format!("mesh {m} primitive {pi}: POSITION accessor {pa} must be VEC3")));
            }
            let nv = pos.values.len() / 3;
            let base = raw.positions.len();
            for c in pos.values.chunks_exact(3) {
                let q = world.transform_point3(DVec3::new(c[0], c[1], c[2]));
                if !q.is_finite() {
                    return Err(ctx.malformed(None, format!("mesh {m} primitive {pi}: a vertex position is not a finite number")));
                }
                raw.positions.push(q);
            }
            drop(pos);
            let indices: Vec<u32> = match p.indices {
                Some(ia) => {
                    let ia = ia.value();
                    bufs.ensure_for_accessor(&root, ia, ctx)?;
                    let ct = accessor(&root, ia, ctx)?.component_type;
                    if !matches!(
                        ct,
                        Checked::Valid(json::accessor::GenericComponentType(ComponentType::U8 | ComponentType::U16 | ComponentType::U32))
                    ) {
                        return Err(ctx.malformed(None, format!("mesh {m} primitive {pi}: index accessor {ia} must use unsigned integers")));
                    }
                    let idx = read_accessor(&root, &bufs, ia, 3 * MAX_TRIANGLES as u64 + 2, ctx)?;
                    if idx.dims != 1 {
                        return Err(ctx.malformed(None, format!("mesh {m} primitive {pi}: index accessor {ia} must be SCALAR")));
                    }
                    let mut out = Vec::with_capacity(idx.values.len());
                    for &v in &idx.values {
                        // Unnormalized unsigned integers: exact in f64.
                        if !(v >= 0.0 && v < nv as f64) {
                            return Err(
                                ctx.malformed(None, format!("mesh {m} primitive {pi}: index {v} is out of range (the primitive has {nv} vertices)"))
                            );
                        }
                        out.push((base + v as usize) as u32);
                    }
                    out
                }
                None => (base as u32..(base + nv) as u32).collect(),
            };
            let before = raw.triangles.len();
            match mode {
                Mode::Triangles => {
                    raw.triangles.extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
                    if !indices.len().is_multiple_of(3) {
                        leftover += 1;
                    }
                }
                Mode::TriangleStrip => {
                    raw.triangles.extend(indices.windows(3).enumerate().map(
                        |(i, w)| {
                            if i % 2 == 0 {
                                [w[0], w[1], w[2]]
                            } else {
                                [w[1], w[0], w[2]]
                            }
                        },
                    ));
                }
                Mode::TriangleFan => {
                    if let Some((&first, rest)) = indices.split_first() {
                        raw.triangles.extend(rest.windows(2).map(|w| [w[0], w[1], first]));
                    }
                }
                _ => {}
            }
            if flip {
                for t in &mut raw.triangles[before..] {
                    t.swap(1, 2);
                }
            }
            raw.source_polygons += raw.triangles.len() - before;
        }
    }
    let plural = |n: usize, what: &str| format!("skipped {n} {what} primitive{}", if n == 1 { "" } else { "s" });
    if points > 0 {
        raw.notes.push(plural(points, "point"));
    }
    if lines > 0 {
        raw.notes.push(plural(lines, "line"));
    }
    if unknown_mode > 0 {
        raw.notes.push(plural(unknown_mode, "unknown-mode"));
    }
    if no_position > 0 {
        raw.notes.push(plural(no_position, "position-less"));
    }
    if leftover > 0 {
        raw.notes.push(format!("{leftover} primitives had an index count not divisible by 3; the extra indices were ignored"));
    }
    Ok(raw)
}
