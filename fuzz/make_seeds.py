#!/usr/bin/env python3
"""Writes the hand-made seed inputs of fuzz/corpus/ (obj, gltf, bspline, design_link).

The protocol seeds (and a few design links) are real encoder output, written by
`cargo test --test fuzz_replay -- --ignored write_seeds`. Run from the repository root:

    python3 fuzz/make_seeds.py

Small files from ../shared/data (the DOS meshes are MIT, the B-splines and hostile inputs were
written for this project) are copied when that folder is there. Nothing here is random.
"""
import base64
import json
import os
import shutil
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")
SHARED = os.path.join(os.path.dirname(ROOT), "shared", "data")


def write(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 20_000, (name, len(data))
    with open(os.path.join(CORPUS, target, name), "wb") as f:
        f.write(data)


def copy(target, src, name=None):
    path = os.path.join(SHARED, src)
    if os.path.exists(path):
        write(target, name or os.path.basename(src), open(path, "rb").read())
    else:
        print(f"skipped {path} (not found)", file=sys.stderr)


# --- OBJ ---------------------------------------------------------------------------------------
write("obj", "tetra.obj", """# a tetrahedron
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
""")
write("obj", "quads_vt_vn.obj", """mtllib x.mtl
o grid
v 0 0 0
v 1 0 0.1
v 2 0 0
v 0 1 0.1
v 1 1 0.3
v 2 1 0.1
vt 0 0
vt 1 1
vn 0 0 1
usemtl m
s off
f 1/1/1 2/2/1 5/2/1 4/1/1
f 2//1 3//1 6//1 5//1
""")
write("obj", "concave_ngon.obj", """# an L-shaped hexagon (ear clipping) and a star (fan fallback)
v 0 0 0
v 2 0 0
v 2 1 0
v 1 1 0
v 1 2 0
v 0 2 0
f 1 2 3 4 5 6
v 3 0 0
v 5 0 0
v 3.5 2 0
v 4 -1 0
v 4.5 2 0
fo -5 -4 -3 -2 -1
""")
write("obj", "negative_continued.obj", """v 0 0 0 \\
  # continued
v 1 0 0
v 1 1 0
v 0 1 1.0e-3
f -4 -3 -2 \\
  -1
l 1 2
p 3
g group
curv 0 1 1 2
f 1 1 2
f 1 2 1 3
""")
write("obj", "welded_duplicates.obj", """v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 0
v 1 0 0.00000000001
v 1 1 0
f 1 2 3
f 4 5 6
f 3 2 1
f 1 2 3
""")
copy("obj", "meshes/tri_dome.obj")
copy("obj", "hostile/remesh_runaway_4faces.obj")
copy("obj", "hostile/tessellation_blowup_saddle18.obj")

# --- glTF / GLB --------------------------------------------------------------------------------
QUAD_POS = [(0, 0, 0), (1, 0, 0), (1, 1, 0.2), (0, 1, 0)]
QUAD_IDX = [0, 1, 2, 0, 2, 3]


def pad4(b, fill=b"\0"):
    return b + fill * (-len(b) % 4)


def f32s(points):
    return b"".join(struct.pack("<3f", *p) for p in points)


def gltf_doc(buffer_uri, blen, extra=None):
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1], "translation": [1, 2, 3], "rotation": [0, 0, 0.7071068, 0.7071068], "scale": [2, 2, 2]},
            {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5, 0, 0, 1]},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0.2]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
        ],
        "buffers": [{"byteLength": blen}],
    }
    if buffer_uri is not None:
        doc["buffers"][0]["uri"] = buffer_uri
    if extra:
        doc.update(extra)
    return doc


def glb(doc, bin_bytes):
    j = pad4(json.dumps(doc, separators=(",", ":")).encode(), b" ")
    chunks = struct.pack("<II", len(j), 0x4E4F534A) + j
    if bin_bytes is not None:
        b = pad4(bin_bytes)
        chunks += struct.pack("<II", len(b), 0x004E4942) + b
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


quad_bin = f32s(QUAD_POS) + struct.pack("<6H", *QUAD_IDX)
uri = "data:application/octet-stream;base64," + base64.b64encode(quad_bin).decode()
write("gltf", "quad.gltf", json.dumps(gltf_doc(uri, len(quad_bin)), indent=1))
write("gltf", "quad.glb", glb(gltf_doc(None, len(quad_bin)), quad_bin))

# Interleaved (byteStride), a strip and a fan without indices, u8 indices, a sparse accessor,
# a points primitive, no scene.
inter = b"".join(struct.pack("<3f4x", *p) for p in QUAD_POS)  # stride 16
strip_pos = f32s([(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0.1), (2, 0, 0)])
idx_u8 = bytes([0, 1, 2, 0, 2, 3]) + b"\0\0"
sparse_idx = struct.pack("<H", 2) + b"\0\0"
sparse_val = struct.pack("<3f", 1, 1, 0.5)
blob = inter + strip_pos + idx_u8 + sparse_idx + sparse_val
o1 = len(inter)
o2 = o1 + len(strip_pos)
o3 = o2 + len(idx_u8)
o4 = o3 + len(sparse_idx)
doc = {
    "asset": {"version": "2.0", "generator": "fuzz seeds"},
    "extensionsUsed": ["KHR_materials_unlit"],
    "meshes": [
        {"primitives": [
            {"attributes": {"POSITION": 0}, "indices": 2},
            {"attributes": {"POSITION": 1}, "mode": 5},
            {"attributes": {"POSITION": 1}, "mode": 6},
            {"attributes": {"POSITION": 3}, "indices": 2},
            {"attributes": {"POSITION": 1}, "mode": 0},
            {"attributes": {"NORMAL": 1}},
        ]},
    ],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5121, "count": 6, "type": "SCALAR"},
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "sparse": {"count": 1, "indices": {"bufferView": 3, "componentType": 5123},
                    "values": {"bufferView": 4}}},
    ],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": len(inter), "byteStride": 16},
        {"buffer": 0, "byteOffset": o1, "byteLength": len(strip_pos)},
        {"buffer": 0, "byteOffset": o2, "byteLength": 6},
        {"buffer": 0, "byteOffset": o3, "byteLength": 2},
        {"buffer": 0, "byteOffset": o4, "byteLength": 12},
    ],
    "buffers": [{"byteLength": len(blob),
                 "uri": "data:application/gltf-buffer;base64," + base64.b64encode(blob).decode()}],
}
write("gltf", "strip_fan_sparse.gltf", json.dumps(doc))

# KHR_mesh_quantization: normalized i16 positions, u32 indices, in a GLB.
qpos = b"".join(struct.pack("<3h2x", *p) for p in [(0, 0, 0), (32767, 0, 0), (32767, 32767, 8000), (0, 32767, -32767)])
qidx = struct.pack("<6I", *QUAD_IDX)
qbin = qpos + qidx
doc = {
    "asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_mesh_quantization"],
    "extensionsRequired": ["KHR_mesh_quantization"],
    "scenes": [{"nodes": [0, 0]}],
    "nodes": [{"mesh": 0, "scale": [1, 1, -1]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [
        {"bufferView": 0, "componentType": 5122, "normalized": True, "count": 4, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"},
    ],
    "bufferViews": [
        {"buffer": 0, "byteLength": len(qpos), "byteStride": 8},
        {"buffer": 0, "byteOffset": len(qpos), "byteLength": len(qidx)},
    ],
    "buffers": [{"byteLength": len(qbin)}],
}
write("gltf", "quantized.glb", glb(doc, qbin))

# --- B-spline JSON -----------------------------------------------------------------------------
for f in ["paraboloid_dome.json", "sphere_patch.json", "cylinder_patch.json", "torus_patch.json",
          "paraboloid_dome_deg5.json", "tunnel_arch.json"]:
    copy("bspline", "bsplines/" + f)
# Textbook knot vectors (n + p + 1), weights, an unknown key.
write("bspline", "textbook_rational.json", json.dumps({
    "degreeU": 1, "degreeV": 2,
    "knotsU": [0, 0, 1, 1], "knotsV": [0, 0, 0, 1, 1, 1],
    "controlPoints": [0, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0.5, 0.7, 1, 1, 0.5, 0.7, 0, 2, 0, 1, 1, 2, 0, 1],
    "name": "seed",
}))

# --- design links ------------------------------------------------------------------------------
copy("design_link", "hostile/design_link_roundtrip_rtol.frag")
copy("design_link", "hostile/design_link_roundtrip_cam.frag")
write("design_link", "empty.frag", "#")
write("design_link", "st_adaptive.frag",
      "#v=1&sample=wave-roof&method=st&jet_degree=3&jet_rings=3&sizing=adaptive&eps=2.5e-4&variant=b"
      "&color=sizing&shading=flat&edges=1&cam=0.6,0.4,3.5,0,0,0.25")
write("design_link", "st_support_faces.frag",
      "#v=1&sample=vault&method=st-support&jet_degree=2&jet_rings=2&opt_r=1&depth=0.1&axis=0.2&rtol=0.001"
      "&remesh=faces&faces=300&color=k1-k2&shading=reflective&edges=0")
write("design_link", "sq.frag",
      "#v=1&sample=torus&method=sq&jet_degree=4&jet_rings=8&theta=12.5&alpha=30&grid=20&rs=5&faces=400"
      "&until=remesh&color=k2&shading=smooth&edges=0")
write("design_link", "own_file.frag",
      "#v=1&sample=file&file=roof%20v2%2B%C3%A9.obj&method=curvature&color=none")
write("design_link", "hostile_values.frag",
      "v=2&sample=nope&method=st&sizing=none&eps=1&faces=7&jet_degree=9&%zz=%41&&edges=2&cam=1,2,-3,4,5,6&x+y=1")
print("seeds written to", CORPUS)
