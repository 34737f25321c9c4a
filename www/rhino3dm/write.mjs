// Spherical Faces → Rhino .3dm, with rhino3dm.js (openNURBS compiled to WebAssembly): the exact
// panels and support elements as rational NURBS surfaces, the edge arcs as rational curves, the
// node axes as lines, m as a point and Ω as a sphere when it is real (a plane Ω as a planar
// surface, in the model's surfaces).
//
// Runs unchanged in the browser (worker) and in Node, like convert.mjs. The model is the JSON the
// Rust side writes (src/export/rhino.rs):
//   {units: "m"|"cm"|"mm"|"ft"|"in",
//    layers: [{name, parent: index|null, color: [r, g, b]}],
//    surfaces: [{layer, name, degree: [p, q], points: [[x, y, z], …] (i along u, v fastest),
//                weights: […], user_text: {key: value}}],
//    curves: [{layer, name, points, weights}], lines: [{layer, name, from, to}],
//    points: [{layer, name, at}], spheres: [{layer, name, center, radius}]}
// Every NURBS is one Bézier span: order = degree + 1, knots 0 (degree times) then 1 (degree times),
// control points set homogeneous (x·w, y·w, z·w, w), as openNURBS stores them.

// Rhino 7's file version, which Rhino 7 and 8 both open (rhino3dm writes 8 by default, which
// Rhino 7 refuses); nothing written here needs 8.
export const FILE_VERSION = 7;

const UNIT_SYSTEMS = { m: 'Meters', cm: 'Centimeters', mm: 'Millimeters', ft: 'Feet', in: 'Inches' };

function bezierKnots(list, degree) {
  for (let k = 0; k < 2 * degree; k++) list.set(k, k < degree ? 0 : 1);
}

function homogeneous(p, w) {
  return [p[0] * w, p[1] * w, p[2] * w, w];
}

function fail(what, name) {
  throw new Error(`${what} ${name}: openNURBS reports it invalid`);
}

/**
 * The .3dm file of `model`.
 * @param {object} model see above
 * @param {object} rhino the initialized rhino3dm module
 * @returns {Uint8Array}
 */
export function write3dm(model, rhino) {
  if (!rhino || typeof rhino.File3dm !== 'function') throw new Error('write3dm: the second argument must be the initialized rhino3dm module');
  const unit = UNIT_SYSTEMS[model.units];
  if (!unit) throw new Error(`write3dm: unknown unit ${JSON.stringify(model.units)}`);
  const doc = new rhino.File3dm();
  doc.settings().modelUnitSystem = rhino.UnitSystem[unit];
  const layerIndex = [];
  for (const l of model.layers ?? []) {
    const layer = new rhino.Layer();
    layer.name = l.name;
    const [r, g, b] = l.color ?? [0, 0, 0];
    layer.color = { r, g, b, a: 255 };
    if (l.parent !== null && l.parent !== undefined) layer.parentLayerId = doc.layers().get(layerIndex[l.parent]).id;
    layerIndex.push(doc.layers().add(layer));
  }
  // One attributes object per kind of item, changed per item (the document copies it); every
  // item of a kind has the same user-text keys, so each overwrites the last.
  const shared = new Map();
  const attributes = (item, kind) => {
    let a = shared.get(kind);
    if (!a) shared.set(kind, (a = new rhino.ObjectAttributes()));
    a.layerIndex = layerIndex[item.layer] ?? 0;
    a.name = item.name ?? '';
    for (const [k, v] of Object.entries(item.user_text ?? {})) a.setUserString(k, String(v));
    return a;
  };
  const objects = doc.objects();
  const add = (geometry, item, kind) => {
    objects.add(geometry, attributes(item, kind));
    geometry.delete();
  };
  for (const s of model.surfaces ?? []) {
    const [p, q] = s.degree;
    const surface = rhino.NurbsSurface.create(3, true, p + 1, q + 1, p + 1, q + 1);
    const [ku, kv, points] = [surface.knotsU(), surface.knotsV(), surface.points()];
    bezierKnots(ku, p);
    bezierKnots(kv, q);
    for (let i = 0; i <= p; i++) {
      for (let j = 0; j <= q; j++) {
        const k = i * (q + 1) + j;
        points.set(i, j, homogeneous(s.points[k], s.weights[k]));
      }
    }
    for (const wrapper of [ku, kv, points]) wrapper.delete();
    if (!surface.isValid) fail('surface', s.name);
    add(surface, s, s.user_text ? 'panel' : 'surface');
  }
  for (const c of model.curves ?? []) {
    const n = c.points.length;
    const curve = new rhino.NurbsCurve(3, true, n, n);
    const [knots, points] = [curve.knots(), curve.points()];
    bezierKnots(knots, n - 1);
    c.points.forEach((pt, k) => points.set(k, homogeneous(pt, c.weights[k])));
    knots.delete();
    points.delete();
    if (!curve.isValid) fail('curve', c.name);
    add(curve, c, 'curve');
  }
  for (const l of model.lines ?? []) add(new rhino.LineCurve(l.from, l.to), l, 'line');
  for (const p of model.points ?? []) add(new rhino.Point(p.at), p, 'point');
  for (const s of model.spheres ?? []) add(new rhino.Sphere(s.center, s.radius).toBrep(), s, 'sphere');
  for (const a of shared.values()) a.delete();
  const options = new rhino.File3dmWriteOptions();
  options.version = FILE_VERSION;
  const bytes = doc.toByteArrayOptions(options);
  options.delete();
  doc.delete();
  return bytes;
}
