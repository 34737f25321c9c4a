#!/usr/bin/env python3
"""Writes the Rhino .3dm test files in this folder from our B-spline JSON files.

    python3 make_3dm.py [BSPLINE_DIR]

BSPLINE_DIR defaults to ../../../../shared/data/bsplines relative to this script (the
sibling checkout's shared/data/bsplines). Needs PyPI's `rhino3dm` (8.x):

    python3 -m venv /tmp/r3venv && /tmp/r3venv/bin/pip install rhino3dm==8.35.0
    /tmp/r3venv/bin/python tests/data/3dm/make_3dm.py

Writes <name>.3dm for tunnel_arch, paraboloid_dome, torus_patch and cylinder_patch (one
NurbsSurface each, named after the file), and mixed.3dm: a line curve, a 3x3-vertex quad mesh
and the surfaces tunnel_arch and torus_patch, in that order, each with an object name.

Conventions (checked below by reading every file back and evaluating it):
- our JSON: (x, y, z) Euclidean, w the weight, U fastest (point (i, j) at 4*(j*nU + i)), knots
  in the openNURBS form (len n + degree - 1); the textbook form (n + degree + 1) is accepted and
  written without its first and last knot.
- rhino3dm's NurbsSurfacePointList[i, j] = Point4d(...) takes HOMOGENEOUS values
  (x*w, y*w, z*w, w) (openNURBS ON_NurbsSurface::SetCV with an ON_4dPoint), so the Euclidean
  point read back is x*w/w, equal to x within an ulp or so, not always bit for bit.
- The .3dm files hold a creation time and random object ids, so they differ between runs;
  the geometry does not.
"""

import json
import math
import os
import sys

import rhino3dm as r

NAMES = ["tunnel_arch", "paraboloid_dome", "torus_patch", "cylinder_patch"]
HERE = os.path.dirname(os.path.abspath(__file__))


def load(path):
    with open(path) as f:
        d = json.load(f)
    pu, pv = int(d["degreeU"]), int(d["degreeV"])
    ku, kv = [float(x) for x in d["knotsU"]], [float(x) for x in d["knotsV"]]
    cp = [float(x) for x in d["controlPoints"]]
    assert len(cp) % 4 == 0, path
    npts = len(cp) // 4
    # Which knot form makes nU * nV = npts (openNURBS first, as src/import/bspline.rs does).
    forms = {"open": lambda n, p: n - p + 1, "textbook": lambda n, p: n - p - 1}
    for fu, fv in [("open", "open"), ("textbook", "textbook"), ("open", "textbook"), ("textbook", "open")]:
        nu, nv = forms[fu](len(ku), pu), forms[fv](len(kv), pv)
        if nu > 0 and nv > 0 and nu * nv == npts:
            break
    else:
        raise SystemExit(f"{path}: knot vectors do not match {npts} control points")
    if fu == "textbook":
        ku = ku[1:-1]
    if fv == "textbook":
        kv = kv[1:-1]
    pts = [cp[4 * k: 4 * k + 4] for k in range(npts)]
    return dict(pu=pu, pv=pv, ku=ku, kv=kv, nu=nu, nv=nv, pts=pts)


def to_rhino(s):
    rational = any(p[3] != 1.0 for p in s["pts"])
    srf = r.NurbsSurface.Create(3, rational, s["pu"] + 1, s["pv"] + 1, s["nu"], s["nv"])
    assert srf is not None
    for k, t in enumerate(s["ku"]):
        srf.KnotsU[k] = t
    for k, t in enumerate(s["kv"]):
        srf.KnotsV[k] = t
    for j in range(s["nv"]):
        for i in range(s["nu"]):
            x, y, z, w = s["pts"][j * s["nu"] + i]
            srf.Points[i, j] = r.Point4d(x * w, y * w, z * w, w)  # homogeneous
    assert srf.IsValid, "rhino3dm says the surface is not valid"
    return srf


# ---- an independent evaluator of our JSON, to check the weight convention by evaluation ----
def basis(knots, p, t):
    """Non-zero B-spline basis functions at t for the textbook knot vector `knots`."""
    n = len(knots) - p - 1
    span = p
    while span < n - 1 and t >= knots[span + 1]:
        span += 1
    N = [0.0] * (p + 1)
    N[0] = 1.0
    left, right = [0.0] * (p + 1), [0.0] * (p + 1)
    for j in range(1, p + 1):
        left[j] = t - knots[span + 1 - j]
        right[j] = knots[span + j] - t
        saved = 0.0
        for k in range(j):
            tmp = N[k] / (right[k + 1] + left[j - k])
            N[k] = saved + right[k + 1] * tmp
            saved = left[j - k] * tmp
        N[j] = saved
    return span, N


def evaluate(s, u, v):
    ku = [s["ku"][0]] + s["ku"] + [s["ku"][-1]]
    kv = [s["kv"][0]] + s["kv"] + [s["kv"][-1]]
    su, Nu = basis(ku, s["pu"], u)
    sv, Nv = basis(kv, s["pv"], v)
    acc = [0.0] * 4
    for b in range(s["pv"] + 1):
        for a in range(s["pu"] + 1):
            i, j = su - s["pu"] + a, sv - s["pv"] + b
            x, y, z, w = s["pts"][j * s["nu"] + i]
            c = Nu[a] * Nv[b] * w
            acc[0] += c * x
            acc[1] += c * y
            acc[2] += c * z
            acc[3] += c
    return [acc[0] / acc[3], acc[1] / acc[3], acc[2] / acc[3]]


def bbox_diag(s):
    lo = [min(p[c] for p in s["pts"]) for c in range(3)]
    hi = [max(p[c] for p in s["pts"]) for c in range(3)]
    return math.dist(lo, hi)


def check(name, s, srf):
    """Compares a surface read back from a file with the JSON source."""
    assert srf.OrderU == s["pu"] + 1 and srf.OrderV == s["pv"] + 1, name
    assert srf.Points.CountU == s["nu"] and srf.Points.CountV == s["nv"], name
    assert list(srf.KnotsU.ToList()) == s["ku"], (name, srf.KnotsU.ToList(), s["ku"])
    assert list(srf.KnotsV.ToList()) == s["kv"], name
    scale = bbox_diag(s)
    worst = 0.0
    for j in range(s["nv"]):
        for i in range(s["nu"]):
            h = srf.Points[i, j]
            x, y, z, w = s["pts"][j * s["nu"] + i]
            assert abs(h.W - w) <= 1e-15 * abs(w), (name, i, j, h.W, w)
            for a, b in zip((h.X / h.W, h.Y / h.W, h.Z / h.W), (x, y, z)):
                worst = max(worst, abs(a - b) / scale)
    assert worst <= 1e-14, (name, worst)
    # Evaluation: rhino3dm's PointAt against our own rational evaluation of the JSON.
    du, dv = srf.Domain(0), srf.Domain(1)
    eworst = 0.0
    for a in range(5):
        for b in range(5):
            u = du.T0 + (du.T1 - du.T0) * (a + 0.37) / 5
            v = dv.T0 + (dv.T1 - dv.T0) * (b + 0.61) / 5
            p = srf.PointAt(u, v)
            q = evaluate(s, u, v)
            eworst = max(eworst, math.dist((p.X, p.Y, p.Z), q) / scale)
    assert eworst <= 1e-12, (name, eworst)
    return worst, eworst


def grid_mesh():
    m = r.Mesh()
    for j in range(3):
        for i in range(3):
            m.Vertices.Add(float(i), float(j), 0.25 * (i - 1) * (j - 1))
    for j in range(2):
        for i in range(2):
            a = j * 3 + i
            m.Faces.AddFace(a, a + 1, a + 4, a + 3)
    return m


def attrs(name):
    a = r.ObjectAttributes()
    a.Name = name
    return a


def new_file():
    f = r.File3dm()
    f.ApplicationName = "Spherical Faces tests/data/3dm/make_3dm.py"
    return f


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "..", "..", "..", "shared", "data", "bsplines")
    surfaces = {}
    for name in NAMES:
        s = load(os.path.join(src, name + ".json"))
        surfaces[name] = s
        f = new_file()
        f.Objects.AddSurface(to_rhino(s), attrs(name))
        out = os.path.join(HERE, name + ".3dm")
        assert f.Write(out, 0), out
        back = r.File3dm.Read(out)
        assert len(back.Objects) == 1
        obj = back.Objects[0]
        assert obj.Attributes.Name == name
        worst, eworst = check(name, s, obj.Geometry)
        print(f"{name}.3dm: {os.path.getsize(out)} bytes, {s['nu']}x{s['nv']} control points, "
              f"degrees {s['pu']},{s['pv']}, max |CP error|/diag {worst:.1e}, max |S error|/diag {eworst:.1e}")

    f = new_file()
    f.Objects.AddLine(r.Point3d(0, 0, 0), r.Point3d(1, 2, 3), attrs("a_line"))
    f.Objects.AddMesh(grid_mesh(), attrs("grid_mesh"))
    f.Objects.AddSurface(to_rhino(surfaces["tunnel_arch"]), attrs("tunnel_arch"))
    f.Objects.AddSurface(to_rhino(surfaces["torus_patch"]), attrs("torus_patch"))
    out = os.path.join(HERE, "mixed.3dm")
    assert f.Write(out, 0), out
    back = r.File3dm.Read(out)
    kinds = [(o.Attributes.Name, type(o.Geometry).__name__) for o in back.Objects]
    assert [k[0] for k in kinds] == ["a_line", "grid_mesh", "tunnel_arch", "torus_patch"], kinds
    for o in back.Objects:
        if o.Attributes.Name in surfaces:
            check(o.Attributes.Name, surfaces[o.Attributes.Name], o.Geometry)
        if o.Attributes.Name == "grid_mesh":
            assert len(o.Geometry.Faces) == 4 and o.Geometry.Faces.QuadCount == 4
    print(f"mixed.3dm: {os.path.getsize(out)} bytes, objects {kinds}")


if __name__ == "__main__":
    main()
