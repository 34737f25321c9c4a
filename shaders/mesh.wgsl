// Spherical Faces viewer: reference surface, its edges, and translucent central spheres.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // Model matrix of the layer's geometry.
    model: mat4x4<f32>,
    eye: vec4<f32>,
    base_color: vec4<f32>,
    // x: min, y: max of the scalar range; z: colour map (0 sequential, 1 diverging);
    // w: for lines, how far (world units) they are pulled toward the eye to win against their faces.
    scalar_range: vec4<f32>,
    // x: shading (0 flat, 1 smooth, 2 reflective); y: colour by scalar (0/1).
    mode: vec4<u32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) scalar: f32,
};

@vertex
fn vs_surface(@location(0) pos: vec3<f32>, @location(1) nrm: vec3<f32>, @location(2) scalar: f32) -> VsOut {
    var o: VsOut;
    let w = u.model * vec4<f32>(pos, 1.0);
    o.world = w.xyz;
    o.normal = normalize((u.model * vec4<f32>(nrm, 0.0)).xyz);
    o.scalar = scalar;
    o.clip = u.view_proj * w;
    return o;
}

// Perceptually ordered sequential map (viridis, polynomial fit).
fn viridis(t: f32) -> vec3<f32> {
    let c0 = vec3<f32>(0.2777, 0.0054, 0.3340);
    let c1 = vec3<f32>(0.1050, 1.4046, 1.3845);
    let c2 = vec3<f32>(-0.3309, 0.2148, 0.0951);
    let c3 = vec3<f32>(-4.6342, -5.7991, -19.3324);
    let c4 = vec3<f32>(6.2283, 14.1799, 56.6906);
    let c5 = vec3<f32>(4.7764, -13.7451, -65.3530);
    let c6 = vec3<f32>(-5.4355, 4.6459, 26.3124);
    return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}

// Diverging blue-white-red map; t = 0.5 is zero.
fn diverging(t: f32) -> vec3<f32> {
    let blue = vec3<f32>(0.23, 0.30, 0.75);
    let white = vec3<f32>(0.87, 0.87, 0.87);
    let red = vec3<f32>(0.71, 0.02, 0.15);
    if (t < 0.5) {
        return mix(blue, white, t * 2.0);
    }
    return mix(white, red, (t - 0.5) * 2.0);
}

fn colormap(s: f32) -> vec3<f32> {
    let span = max(u.scalar_range.y - u.scalar_range.x, 1e-30);
    let t = clamp((s - u.scalar_range.x) / span, 0.0, 1.0);
    if (u.scalar_range.z > 0.5) {
        return diverging(t);
    }
    return clamp(viridis(t), vec3<f32>(0.0), vec3<f32>(1.0));
}

// A studio environment with soft light bars: reflections reveal kinks and waviness, the way
// glass panels will.
fn environment(r: vec3<f32>) -> vec3<f32> {
    let up = r.z;
    let sky = mix(vec3<f32>(0.55, 0.60, 0.68), vec3<f32>(0.16, 0.20, 0.30), clamp(up, 0.0, 1.0));
    let ground = mix(vec3<f32>(0.30, 0.28, 0.26), vec3<f32>(0.10, 0.10, 0.11), clamp(-up, 0.0, 1.0));
    var c = select(ground, sky, up >= 0.0);
    let az = atan2(r.y, r.x);
    let bars = smoothstep(0.80, 0.98, cos(az * 6.0)) * smoothstep(-0.1, 0.25, up) * (1.0 - smoothstep(0.6, 0.9, up));
    c = c + vec3<f32>(1.6) * bars;
    let horizon = exp(-abs(up) * 30.0);
    c = c + vec3<f32>(0.35) * horizon;
    return c;
}

fn shade(world: vec3<f32>, interp_normal: vec3<f32>, base: vec3<f32>) -> vec3<f32> {
    var n = normalize(interp_normal);
    if (u.mode.x == 0u) {
        n = normalize(cross(dpdx(world), dpdy(world)));
    }
    let v = normalize(u.eye.xyz - world);
    // Open surfaces are seen from both sides.
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    if (u.mode.x == 2u) {
        let r = reflect(-v, n);
        let fresnel = 0.08 + 0.92 * pow(1.0 - max(dot(n, v), 0.0), 5.0);
        let env = environment(r);
        return mix(base * 0.35, env, 0.55 + 0.45 * fresnel);
    }
    let key = normalize(v + vec3<f32>(0.3, 0.2, 0.6));
    let diffuse = max(dot(n, key), 0.0);
    let h = normalize(key + v);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * 0.25;
    let fill = 0.5 + 0.5 * n.z;
    return base * (0.22 + 0.62 * diffuse + 0.16 * fill) + vec3<f32>(spec);
}

@fragment
fn fs_surface(i: VsOut) -> @location(0) vec4<f32> {
    var base = u.base_color.rgb;
    if (u.mode.y == 1u) {
        base = colormap(i.scalar);
    }
    return vec4<f32>(shade(i.world, i.normal, base), 1.0);
}

@vertex
fn vs_edges(@location(0) pos: vec3<f32>) -> @builtin(position) vec4<f32> {
    let world = (u.model * vec4<f32>(pos, 1.0)).xyz;
    // Pull lines slightly toward the eye so they win the depth test against their own faces.
    let toward = normalize(u.eye.xyz - world);
    return u.view_proj * vec4<f32>(world + toward * u.scalar_range.w, 1.0);
}

@fragment
fn fs_edges() -> @location(0) vec4<f32> {
    return u.base_color;
}

@fragment
fn fs_overlay(i: VsOut) -> @location(0) vec4<f32> {
    let n = normalize(i.normal);
    let v = normalize(u.eye.xyz - i.world);
    let rim = pow(1.0 - abs(dot(n, v)), 2.0);
    let c = u.base_color.rgb * (0.55 + 0.45 * abs(dot(n, v))) + vec3<f32>(0.5) * rim;
    return vec4<f32>(c, u.base_color.a * (0.6 + 0.4 * rim));
}
