"""Writes the hostile-input corpus next to this script: small files that each attack one bound
(fans, huge polygons, slivers, flaps, out-of-range scales, control characters, lying size
fields). `tests/hostile.rs` runs every file here (and in ../shared/data/hostile) through import,
`info` and each method. Run: python3 tests/data/hostile/make_corpus.py"""
import base64, json, math, os, struct

here = os.path.dirname(os.path.abspath(__file__))


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(here, name), mode) as f:
        f.write(data)


def dome(n=12):
    v, f = [], []
    for j in range(n):
        for i in range(n):
            x, y = i / (n - 1), j / (n - 1)
            v.append((x, y, 0.5 - ((x - .5) ** 2 + (y - .5) ** 2)))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i + 1
            f += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
    return v, f


def obj(v, f, extra=""):
    return "".join("v %.10g %.10g %.10g\n" % p for p in v) + "".join("f " + " ".join(map(str, t)) + "\n" for t in f) + extra


# A fan of 5000 triangles around one apex: a vertex of valence 5000 (jet fitting was quadratic in it).
n = 5000
v = [(0.0, 0.0, 0.3)] + [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0.0) for k in range(n)]
write("fan_5000.obj", obj(v, [(1, k + 2, (k + 1) % n + 2) for k in range(n)]))

# One OBJ polygon of 1500 corners (triangulated without a hub).
n = 1500
v = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0.1 * math.sin(3 * 2 * math.pi * k / n)) for k in range(n)]
write("ngon_1500.obj", obj(v, [tuple(range(1, n + 1))]))

# A dome with one sliver triangle glued to a boundary edge (height 1e-6 of its length).
v, f = dome()
a, b = v[0], v[1]
v.append(tuple(0.5 * (p + q) for p, q in zip(a, b)))
v[-1] = (v[-1][0], v[-1][1] - 1e-7, v[-1][2])
f.append((2, 1, len(v)))
write("sliver_dome.obj", obj(v, f))

# A dome with a flap folded back over a boundary edge.
v, f = dome()
v.append((0.5, 0.5, 2.0))
f.append((1, 2, len(v)))
write("flap_dome.obj", obj(v, f))

# Out-of-range scales.
write("huge_scale.obj", "v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nv 1e200 1e200 1e199\nf 1 2 4\nf 1 4 3\n")
write("tiny_scale.obj", "v 0 0 0\nv 1e-200 0 0\nv 0 1e-200 0\nv 1e-200 1e-200 1e-201\nf 1 2 4\nf 1 4 3\n")

# Control characters in a number (an ANSI clear-screen) and in a B-spline key.
write("control_chars.obj", "v 0 0 0\nv 1\x1b[2J 0 0\nv 0 1 0\nf 1 2 3\n")
write("control_chars.json", '{"degreeU": 1, "degreeV": 1, "knotsU": [0, 1], "knotsV": [0, 1], "controlPoints": "\x1b[2J\x07"}')

# Lying size fields: a glTF accessor of 6 M vertices with no bufferView; a GLB whose chunk length
# runs past the file; a B-spline whose knots promise more points than it has.
positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
gltf = {
    "asset": {"version": "2.0"},
    "buffers": [{"byteLength": len(positions), "uri": "data:application/octet-stream;base64," + base64.b64encode(positions).decode()}],
    "bufferViews": [{"buffer": 0, "byteLength": len(positions)}],
    "accessors": [
        {"componentType": 5126, "count": 6000000, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    ],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "nodes": [{"mesh": 0}],
    "scenes": [{"nodes": [0]}],
}
write("lying_accessor.gltf", json.dumps(gltf))
body = json.dumps({"asset": {"version": "2.0"}}).encode()
body += b" " * (-len(body) % 4)
write("lying_chunk.glb", struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(body)) + struct.pack("<I4s", 0x7FFFFFF0, b"JSON") + body)
write("lying_knots.json", json.dumps({"degreeU": 3, "degreeV": 3, "knotsU": [0] * 3 + [1] * 3 + [2] * 100, "knotsV": [0, 0, 0, 1, 1, 1],
                                       "controlPoints": [0, 0, 0, 1] * 16}))
