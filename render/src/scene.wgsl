// Scene shader: Gaussian dimples bend deformable objects in the vertex stage; lighting is done in
// linear space and the sRGB render target encodes it on store (or `fs_encoded` does).

const MAX_DIMPLES: u32 = 4u;

struct Globals {
    view_proj: mat4x4<f32>,
    eye_m: vec4<f32>,
    // xyz: unit direction towards the key light; w: ambient strength.
    key_dir: vec4<f32>,
    // xyz centre (m), w radius (m).
    dimple_centre: array<vec4<f32>, 4>,
    // xyz outward normal, w depth (m).
    dimple_normal: array<vec4<f32>, 4>,
    // x: dimple count.
    counts: vec4<u32>,
};

struct Object {
    model: mat4x4<f32>,
    normal_model: mat4x4<f32>,
    color: vec4<f32>,
    // x roughness, y detail period (m), z specular, w shininess.
    surface: vec4<f32>,
    // x: 1 when deformable.
    flags: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
@group(1) @binding(0) var<uniform> object: Object;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_m: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    // Undeformed world position: the procedural detail sticks to the material, not to space.
    @location(3) rest_m: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    let rest = (object.model * vec4<f32>(v.position, 1.0)).xyz;
    var world = rest;
    var n = normalize((object.normal_model * vec4<f32>(v.normal, 0.0)).xyz);
    // Every dimple slot is evaluated and the unused or undeformable ones weigh 0: a branch or a
    // loop bound on a uniform makes lavapipe compile a new shader whenever that uniform changes,
    // which is every draw.
    let deformable = select(0.0, 1.0, object.flags.x > 0.5);
    var tilt = vec3<f32>(0.0);
    for (var i = 0u; i < MAX_DIMPLES; i = i + 1u) {
        let c = globals.dimple_centre[i];
        let a = globals.dimple_normal[i];
        let weight = select(0.0, deformable, i < globals.counts.x);
        let radius = max(c.w, 1e-6);
        let rel = rest - c.xyz;
        let along = dot(rel, a.xyz);
        let perp = rel - along * a.xyz;
        let f = weight * a.w * exp(-dot(perp, perp) / (radius * radius)) * exp(-max(-along, 0.0) / (2.0 * radius));
        world = world - a.xyz * f;
        // Gradient of the displacement: walls of the dimple lean towards its centre. Only
        // faces turned towards the indenter tilt; side walls keep their normals.
        tilt = tilt - 2.0 * f * perp / (radius * radius) * max(dot(n, a.xyz), 0.0);
    }
    n = select(n, normalize(n + tilt), deformable > 0.0);
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    out.world_m = world;
    out.normal = n;
    out.color = v.color * object.color;
    out.rest_m = rest;
    return out;
}

fn hash3(p: vec3<f32>) -> f32 {
    let q = fract(p * 0.3183099 + vec3<f32>(0.1, 0.2, 0.3)) * 17.0;
    return fract(q.x * q.y * q.z * (q.x + q.y + q.z));
}

// Value noise in 0..1 with smooth interpolation (x) and its analytic gradient (yzw): one set of
// eight hashes per fragment instead of four noise evaluations for a finite-difference slope.
fn noise3_grad(p: vec3<f32>) -> vec4<f32> {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let du = 6.0 * f * (1.0 - f);
    let n000 = hash3(i);
    let n100 = hash3(i + vec3<f32>(1.0, 0.0, 0.0));
    let n010 = hash3(i + vec3<f32>(0.0, 1.0, 0.0));
    let n110 = hash3(i + vec3<f32>(1.0, 1.0, 0.0));
    let n001 = hash3(i + vec3<f32>(0.0, 0.0, 1.0));
    let n101 = hash3(i + vec3<f32>(1.0, 0.0, 1.0));
    let n011 = hash3(i + vec3<f32>(0.0, 1.0, 1.0));
    let n111 = hash3(i + vec3<f32>(1.0, 1.0, 1.0));
    // Trilinear interpolation written as a polynomial in u, so it differentiates term by term.
    let k1 = n100 - n000;
    let k2 = n010 - n000;
    let k3 = n001 - n000;
    let k4 = n000 - n100 - n010 + n110;
    let k5 = n000 - n010 - n001 + n011;
    let k6 = n000 - n100 - n001 + n101;
    let k7 = -n000 + n100 + n010 - n110 + n001 - n101 - n011 + n111;
    let value = n000 + k1 * u.x + k2 * u.y + k3 * u.z + k4 * u.x * u.y + k5 * u.y * u.z + k6 * u.z * u.x
        + k7 * u.x * u.y * u.z;
    let grad = du * vec3<f32>(
        k1 + k4 * u.y + k6 * u.z + k7 * u.y * u.z,
        k2 + k5 * u.z + k4 * u.x + k7 * u.z * u.x,
        k3 + k6 * u.x + k5 * u.y + k7 * u.x * u.y,
    );
    return vec4<f32>(value, grad);
}

fn shade(in: VertexOut, front: bool) -> vec4<f32> {
    var n = normalize(in.normal);
    if !front {
        n = -n;
    }
    // Smooth surfaces (roughness 0) evaluate the detail too and weigh it 0, for the reason
    // given in the vertex shader.
    let roughness = max(object.surface.x, 0.0);
    let p = in.rest_m / max(object.surface.y, 1e-5);
    let noise = noise3_grad(p);
    let h = noise.x;
    let grad = noise.yzw;
    // Bump: remove the normal's own component so only the tangential slope tilts it.
    let slope = grad - dot(grad, n) * n;
    n = normalize(n - roughness * 0.8 * slope);
    let base = in.color.rgb * (1.0 - roughness * 0.35 * (h - 0.5) * 2.0);
    let view = normalize(globals.eye_m.xyz - in.world_m);
    let key = globals.key_dir.xyz;
    let fill = normalize(vec3<f32>(-0.5, 0.4, -0.6));
    let diffuse = max(dot(n, key), 0.0) * 0.85 + max(dot(n, fill), 0.0) * 0.25;
    // Hemisphere ambient: brighter from above.
    let ambient = globals.key_dir.w * mix(0.5, 1.0, n.y * 0.5 + 0.5);
    let half_vec = normalize(key + view);
    let spec = object.surface.z * pow(max(dot(n, half_vec), 0.0), object.surface.w);
    let rgb = base * (ambient + diffuse) + vec3<f32>(spec);
    return vec4<f32>(rgb, in.color.a);
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return shade(in, front);
}

// The tool where tissue hides it (depth test "greater"): drawn half-transparent and tinted so the
// shaft inside punctured tissue reads clearly through several see-through layers.
@fragment
fn fs_xray(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let lit = shade(in, front);
    return vec4<f32>(mix(lit.rgb, vec3<f32>(0.55, 0.8, 1.0), 0.35), 0.7);
}

// The sRGB transfer function (IEC 61966-2-1), for opaque surfaces drawn into a multisampled
// target viewed without its sRGB format: encoded once per pixel here instead of once per sample
// on store, which lavapipe does in software (see `Renderer::encoded_opaque`).
fn encode_srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x, x <= vec3<f32>(0.0031308));
}

@fragment
fn fs_encoded(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let c = shade(in, front);
    return vec4<f32>(encode_srgb(c.rgb), c.a);
}
