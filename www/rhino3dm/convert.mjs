// Rhino .3dm → Spherical Faces input, with rhino3dm.js (openNURBS compiled to WebAssembly).
//
// Runs unchanged in the browser (page or worker) and in Node: no Node-only import at the top
// level. The caller hands in an initialized rhino3dm module: `loadRhino(baseUrl)` below in the
// browser, or `await (await import('rhino3dm')).default()` in Node (see cli.mjs).
//
// Output per object:
// - surfaces: our B-spline JSON (src/import/bspline.rs): degreeU/V = order − 1, knotsU/V exactly
//   as openNURBS stores them (n + degree − 1 knots), controlPoints x, y, z, w with U fastest,
//   (x, y, z) Euclidean = homogeneous / w. rhino3dm.js's NurbsSurface.points().get(i, j) returns
//   the HOMOGENEOUS 4-D control point (x·w, y·w, z·w, w) (openNURBS GetCV with an ON_4dPoint).
// - meshes: OBJ text, `v x y z` and `f a b c [d]` (1-based; a Rhino face whose last two indices
//   are equal is a triangle).

/** The files of the npm package rhino3dm that a browser needs, side by side in one folder. */
export const RHINO_BROWSER_FILES = ['rhino3dm.module.js', 'rhino3dm.wasm'];

/** Every .3dm file starts with these 24 bytes, then an 8-character version field. */
const MAGIC = '3D Geometry File Format ';

/**
 * Loads and initializes rhino3dm.js in the browser (or in Node from a file: URL).
 * `baseUrl` is the folder that serves rhino3dm.module.js and rhino3dm.wasm, absolute or relative
 * to the document (or worker) URL.
 */
export async function loadRhino(baseUrl, { script = 'rhino3dm.module.js' } = {}) {
  const here = globalThis.document?.baseURI ?? globalThis.location?.href ?? import.meta.url;
  const base = new URL(String(baseUrl).replace(/\/*$/, '/'), here).href;
  let factory;
  try {
    factory = (await import(/* @vite-ignore */ /* webpackIgnore: true */ new URL(script, base).href)).default;
  } catch (e) {
    throw new Error(`could not load rhino3dm.js from ${new URL(script, base).href}: ${e?.message ?? e}`);
  }
  if (typeof factory !== 'function') throw new Error(`${new URL(script, base).href} does not export the rhino3dm factory`);
  try {
    return await factory({ locateFile: (file) => new URL(file, base).href });
  } catch (e) {
    throw new Error(`could not start rhino3dm.wasm from ${base}: ${e?.message ?? e}`);
  }
}

/**
 * Reads a .3dm file and converts every NURBS-able surface and every mesh in it.
 * @param {Uint8Array|ArrayBuffer|ArrayBufferView} bytes the file
 * @param {object} rhino the initialized rhino3dm module
 * @returns {Promise<{objects: {index:number, name:string, kind:'surface'|'mesh', summary:string, text:string}[], notes:string[]}>}
 */
export async function read3dm(bytes, rhino) {
  if (!rhino || typeof rhino.File3dm?.fromByteArray !== 'function') {
    throw new Error('read3dm: the second argument must be the initialized rhino3dm module');
  }
  const data = asBytes(bytes);
  if (data.length < MAGIC.length + 8) {
    throw new Error(`not a readable Rhino .3dm file: only ${data.length} bytes`);
  }
  const head = String.fromCharCode(...data.subarray(0, MAGIC.length));
  if (head !== MAGIC) {
    throw new Error(`not a readable Rhino .3dm file: it does not start with "${MAGIC.trim()}"`);
  }
  const damage = checkChunks(data);
  if (damage) throw new Error(`not a readable Rhino .3dm file: ${damage}`);
  const trash = []; // embind handles to free at the end (wasm memory is not garbage-collected)
  const keep = (x) => {
    if (x && typeof x.delete === 'function') trash.push(x);
    return x;
  };
  try {
    let doc;
    try {
      doc = keep(rhino.File3dm.fromByteArray(data));
    } catch (e) {
      throw new Error(`not a readable Rhino .3dm file: rhino3dm failed (${e?.message ?? e})`);
    }
    if (!doc) throw new Error('not a readable Rhino .3dm file: openNURBS could not read it (damaged, truncated or not a .3dm)');
    return convertDoc(doc, rhino, keep);
  } finally {
    for (const x of trash.reverse()) {
      try {
        x.delete();
      } catch {
        /* already freed */
      }
    }
  }
}

function convertDoc(doc, rhino, keep) {
  const objects = [];
  const notes = [];
  const skipped = new Map(); // type name → count
  const skip = (type) => skipped.set(type, (skipped.get(type) ?? 0) + 1);
  const table = keep(doc.objects());
  const count = table.count;
  let inBlocks = 0;
  const trimmed = [];
  const reversed = [];

  for (let i = 0; i < count; i++) {
    const obj = keep(table.get(i));
    const geom = obj && keep(obj.geometry());
    if (!geom) {
      skip('empty object');
      continue;
    }
    const attrs = keep(obj.attributes());
    if (attrs?.isInstanceDefinitionObject) {
      inBlocks++;
      continue;
    }
    const type = typeName(rhino, geom);
    const label = (attrs?.name ?? '').trim() || `${type} ${i}`;
    const push = (kind, name, summary, text) => objects.push({ index: objects.length, name, kind, summary, text });

    if (geom instanceof rhino.Mesh) {
      const { text, summary } = meshToObj(geom, keep, `${label} (object ${i})`);
      if (text) push('mesh', label, summary, text);
      else notes.push(`object ${i} "${label}": a mesh without faces, skipped`);
    } else if (geom instanceof rhino.Brep) {
      const faces = keep(geom.faces());
      for (let f = 0; f < faces.count; f++) {
        const face = keep(faces.get(f));
        const name = faces.count > 1 ? `${label} face ${f}` : label;
        const dup = keep(face.duplicateFace(false));
        if (dup && !dup.isSurface) trimmed.push(name);
        if (face.orientationIsReversed) reversed.push(name);
        const srf = keep(face.underlyingSurface());
        const ns = srf && keep(srf.toNurbsSurface());
        if (!ns) {
          notes.push(`${name}: its surface has no NURBS form, skipped`);
          continue;
        }
        const { text, summary } = nurbsToJson(ns, keep);
        push('surface', name, `${summary}; from ${type.toLowerCase()} object ${i}${faces.count > 1 ? ` face ${f} of ${faces.count}` : ''}`, text);
      }
    } else if (geom instanceof rhino.Extrusion) {
      if (geom.capCount === 0 && geom.profileCount === 1) {
        const ns = keep(geom.toNurbsSurface());
        if (!ns) {
          notes.push(`object ${i} "${label}": an extrusion without NURBS form, skipped`);
          continue;
        }
        const { text, summary } = nurbsToJson(ns, keep);
        push('surface', label, `${summary}; from extrusion object ${i}`, text);
      } else {
        const brep = keep(geom.toBrep(false));
        const faces = brep && keep(brep.faces());
        if (!faces) {
          notes.push(`object ${i} "${label}": an extrusion without a brep form, skipped`);
          continue;
        }
        for (let f = 0; f < faces.count; f++) {
          const face = keep(faces.get(f));
          const name = `${label} face ${f}`;
          const dup = keep(face.duplicateFace(false));
          if (dup && !dup.isSurface) trimmed.push(name);
          if (face.orientationIsReversed) reversed.push(name);
          const ns = keep(keep(face.underlyingSurface())?.toNurbsSurface());
          if (!ns) continue;
          const { text, summary } = nurbsToJson(ns, keep);
          push('surface', name, `${summary}; from extrusion object ${i} face ${f} of ${faces.count}`, text);
        }
      }
    } else if (geom instanceof rhino.Surface) {
      // NurbsSurface, PlaneSurface, RevSurface, SumSurface, …
      const ns = geom instanceof rhino.NurbsSurface ? geom : keep(geom.toNurbsSurface());
      if (!ns) {
        notes.push(`object ${i} "${label}": a ${type} without NURBS form, skipped`);
        continue;
      }
      const { text, summary } = nurbsToJson(ns, keep);
      const what = geom instanceof rhino.NurbsSurface ? '' : `; converted from ${geom.constructor?.name && geom.constructor.name !== 'ctor' ? geom.constructor.name : type}`;
      push('surface', label, `${summary}${what}`, text);
    } else {
      skip(type);
    }
  }

  if (trimmed.length) {
    notes.push(`trims ignored: ${listSome(trimmed)} ${trimmed.length === 1 ? 'is a trimmed face' : 'are trimmed faces'}; the whole untrimmed surface is imported`);
  }
  if (reversed.length) {
    notes.push(`${listSome(reversed)}: the face is reversed against its surface; the surface's own orientation (normal = S_u × S_v) is used`);
  }
  if (inBlocks) notes.push(`${inBlocks} object(s) inside block definitions skipped`);
  const skippedText = [...skipped].map(([t, n]) => `${n} ${t}`).join(', ');
  if (skippedText) notes.push(`skipped (not a surface or mesh): ${skippedText}`);
  // The model's unit system by its Rhino name ("Millimeters", "Feet"), or null.
  let units = null;
  try {
    const settings = keep(doc.settings());
    const name = enumName(rhino.UnitSystem, settings?.modelUnitSystem);
    if (name && name !== 'None') {
      units = name;
      notes.push(`model units: ${name}`);
    }
  } catch {
    /* settings are optional */
  }

  if (!objects.length) {
    const holds = count === 0 ? 'no objects' : [skippedText, inBlocks ? `${inBlocks} object(s) in block definitions` : ''].filter(Boolean).join(', ') || 'nothing usable';
    throw new Error(`no NURBS surface or mesh in this .3dm file; it holds: ${holds}`);
  }
  return { objects, notes, units };
}

/** Our B-spline JSON of a rhino3dm NurbsSurface. */
function nurbsToJson(ns, keep) {
  const pu = ns.orderU - 1;
  const pv = ns.orderV - 1;
  const ku = keep(ns.knotsU());
  const kv = keep(ns.knotsV());
  const knotsU = Array.from(ku.toList());
  const knotsV = Array.from(kv.toList());
  const pts = keep(ns.points());
  const nu = pts.countU;
  const nv = pts.countV;
  if (knotsU.length !== nu + pu - 1 || knotsV.length !== nv + pv - 1) {
    throw new Error(`unexpected knot count from rhino3dm: ${knotsU.length}×${knotsV.length} knots for ${nu}×${nv} points of degree ${pu}×${pv}`);
  }
  const rational = !!ns.isRational;
  const cp = new Array(4 * nu * nv);
  let k = 0;
  let wMin = Infinity;
  let wMax = -Infinity;
  for (let j = 0; j < nv; j++) {
    for (let i = 0; i < nu; i++) {
      const p = pts.get(i, j); // homogeneous [X, Y, Z, W]
      const w = rational ? p[3] : 1;
      if (!(w > 0) || !Number.isFinite(w)) throw new Error(`control point (${i}, ${j}) has weight ${w}`);
      cp[k++] = rational ? p[0] / w : p[0];
      cp[k++] = rational ? p[1] / w : p[1];
      cp[k++] = rational ? p[2] / w : p[2];
      cp[k++] = w;
      wMin = Math.min(wMin, w);
      wMax = Math.max(wMax, w);
    }
  }
  const text = JSON.stringify({ degreeU: pu, degreeV: pv, knotsU, knotsV, controlPoints: cp });
  const dom = (kn, p) => `[${fmt(kn[p - 1])}, ${fmt(kn[kn.length - p])}]`;
  const rat = rational ? (wMin === wMax ? `rational, w = ${fmt(wMin)}` : `rational, w ${fmt(wMin)}…${fmt(wMax)}`) : 'non-rational';
  const summary = `NURBS surface, degree ${pu}×${pv}, ${nu}×${nv} control points, ${rat}, domain ${dom(knotsU, pu)} × ${dom(knotsV, pv)}`;
  return { text, summary };
}

/** OBJ text of a rhino3dm Mesh (triangles and quads; n-gons come as their triangles/quads). */
function meshToObj(mesh, keep, title) {
  const verts = keep(mesh.vertices());
  const faces = keep(mesh.faces());
  const nv = verts.count;
  const lines = [`# ${title.replace(/[\r\n]/g, ' ')}, from a Rhino .3dm file`];
  for (let i = 0; i < nv; i++) {
    const p = verts.get(i);
    lines.push(`v ${num32(p[0])} ${num32(p[1])} ${num32(p[2])}`);
  }
  let tris = 0;
  let quads = 0;
  let bad = 0;
  for (let f = 0; f < faces.count; f++) {
    const [a, b, c, d] = faces.get(f);
    const ok = (x) => Number.isInteger(x) && x >= 0 && x < nv;
    if (![a, b, c, d].every(ok)) {
      bad++;
      continue;
    }
    if (c === d) {
      lines.push(`f ${a + 1} ${b + 1} ${c + 1}`);
      tris++;
    } else {
      lines.push(`f ${a + 1} ${b + 1} ${c + 1} ${d + 1}`);
      quads++;
    }
  }
  if (!tris && !quads) return { text: '', summary: '' };
  const summary = `mesh, ${nv} vertices, ${tris + quads} faces (${quads} quads, ${tris} triangles)${bad ? `, ${bad} faces with bad indices dropped` : ''}`;
  return { text: lines.join('\n') + '\n', summary };
}

/**
 * rhino3dm.js hands out mesh vertices as float32 values widened to double
 * (0.1 → 0.10000000149011612). Such a value is written as the shortest decimal that reads back
 * to the same float32 ("0.1"); any other value in full double precision.
 */
function num32(x) {
  if (Math.fround(x) === x && Number.isFinite(x)) {
    for (let p = 1; p <= 9; p++) {
      const s = x.toPrecision(p);
      if (Math.fround(Number(s)) === x) return String(Number(s));
    }
  }
  return String(x);
}

// openNURBS chunk typecodes (opennurbs_3dm.h).
const TCODE_SHORT = 0x80000000;
const TCODE_TABLE = 0x10000000;
const TCODE_ENDOFTABLE = 0xffffffff;
const TCODE_ENDOFFILE = 0x00007fff;

/**
 * A fast structural check of a version 5+ .3dm file before openNURBS sees it: the top-level
 * chunks must tile the file up to the end-of-file chunk, and the records of every table must tile
 * the table up to its end-of-table chunk. openNURBS can spend half a minute (growing its heap to
 * 2 GB) on a file whose chunk lengths are damaged; this turns those into a quick error.
 * Returns a description of the damage, or '' (also for pre-version-5 files, not checked).
 */
function checkChunks(data) {
  const version = Number(String.fromCharCode(...data.subarray(24, 32)).trim());
  if (!Number.isInteger(version) || version <= 0) return 'bad version field in the header';
  if (version < 50) return ''; // 4-byte chunk lengths; left to openNURBS
  const view = new DataView(data.buffer, data.byteOffset, data.byteLength);
  const chunkAt = (p, end) => {
    if (p + 12 > end) return null;
    const tc = view.getUint32(p, true);
    const len = view.getBigUint64(p + 4, true);
    const size = tc & TCODE_SHORT ? 0n : len;
    if (BigInt(p + 12) + size > BigInt(end)) return null;
    return { tc: tc >>> 0, size: Number(size), next: p + 12 + Number(size) };
  };
  let p = 32;
  for (;;) {
    const c = chunkAt(p, data.length);
    if (!c) {
      return p >= data.length
        ? 'truncated (no end-of-file mark)'
        : `damaged or truncated: the chunk at byte ${p} runs past the end of the file`;
    }
    if (c.tc === TCODE_ENDOFFILE) return '';
    if (c.tc & TCODE_TABLE && !(c.tc & TCODE_SHORT)) {
      let q = p + 12;
      const end = c.next;
      let closed = false;
      while (q < end) {
        const r = chunkAt(q, end);
        if (!r) return `damaged: a record at byte ${q} runs past the end of its table`;
        if (r.tc === TCODE_ENDOFTABLE) closed = true;
        q = r.next;
      }
      if (!closed) return `damaged: the table at byte ${p} has no end-of-table mark`;
    }
    p = c.next;
  }
}

function fmt(x) {
  return String(Number(x.toPrecision(6)));
}

function listSome(names) {
  const shown = names.slice(0, 5).map((n) => `"${n}"`).join(', ');
  return names.length > 5 ? `${shown} and ${names.length - 5} more` : shown;
}

function enumName(en, value) {
  if (!en || value === undefined || value === null) return undefined;
  return Object.keys(en).find((k) => k !== 'values' && k !== 'argCount' && en[k] === value);
}

function typeName(rhino, geom) {
  const ctor = geom?.constructor?.name;
  // embind class names survive in most builds; the minified ones say "ctor".
  for (const cls of ['NurbsSurface', 'PlaneSurface', 'RevSurface', 'Extrusion', 'Brep', 'Mesh', 'SubD', 'NurbsCurve', 'PolyCurve', 'PolylineCurve', 'LineCurve', 'ArcCurve', 'Point', 'PointCloud', 'TextDot', 'Hatch', 'InstanceReference', 'Light', 'AnnotationBase', 'Curve', 'Surface']) {
    if (rhino[cls] && geom instanceof rhino[cls]) return cls === 'AnnotationBase' ? 'Annotation' : cls;
  }
  return enumName(rhino.ObjectType, geom?.objectType) ?? (ctor && ctor !== 'ctor' ? ctor : 'unknown object');
}

function asBytes(bytes) {
  if (bytes instanceof Uint8Array) return bytes;
  if (bytes instanceof ArrayBuffer) return new Uint8Array(bytes);
  if (ArrayBuffer.isView(bytes)) return new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  throw new Error('read3dm: expected the file as a Uint8Array or ArrayBuffer');
}
