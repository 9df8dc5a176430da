// Geometry pass of the wgpu camera. Everything is shaded in the camera (optical) frame:
// x right, y down, z forward. Lines starting with `#if FLAG ...` / `#else` / `#endif` are
// resolved on the CPU before compilation (a block is kept when any listed flag is on), and
// `LOC_*` names are replaced by the colour attachment locations of the variant. With no
// output at all only the vertex stage remains (the depth pre-pass).

struct Light {
    // xyz: position (point, w = 1) or direction towards the light (directional, w = 0).
    pos: vec4<f32>,
    // rgb: colour × intensity (candela or lux).
    color: vec4<f32>,
}

struct Camera {
    // clip = (proj.x * x, -proj.y * y, proj.z * z + proj.w, z)  (reversed depth).
    proj: vec4<f32>,
    // fx, fy, cx, cy in pixels.
    pix: vec4<f32>,
    // xyz: world up in the camera frame; w: exposure.
    up: vec4<f32>,
    // Sky and ground radiance of the ambient light (rgb).
    sky: vec4<f32>,
    ground: vec4<f32>,
    // Camera frame to shadow-map clip space.
    shadow: mat4x4<f32>,
    // x: light count; y: shadow light index + 1 (0: none); z: shadow map size.
    counts: vec4<u32>,
    lights: array<Light, 8>,
}

struct Material {
    color: vec4<f32>,
    metallic: f32,
    roughness: f32,
    semantic: u32,
    instance: u32,
}

@group(0) @binding(0) var<uniform> cam: Camera;
// Per item: 3 rows of the current model-view (item frame to camera frame), then 3 rows of the
// previous one.
@group(0) @binding(1) var<storage, read> xf: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
#if SHADOW
@group(0) @binding(3) var shadow_map: texture_depth_2d;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
#endif

struct VsOut {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) @interpolate(flat) item: u32,
#if RGB DEPTH NORMAL SFLOW OFLOW
    @location(1) p: vec3<f32>,
#endif
#if RGB NORMAL
    @location(2) n: vec3<f32>,
#endif
#if SFLOW OFLOW
    @location(3) q: vec3<f32>,
#endif
}

@vertex
fn vs_main(@location(0) pos: vec3<f32>, @location(1) nrm: vec4<f32>, @location(2) item: u32) -> VsOut {
    var out: VsOut;
    let b = item * 6u;
    let h = vec4<f32>(pos, 1.0);
    let r0 = xf[b];
    let r1 = xf[b + 1u];
    let r2 = xf[b + 2u];
    let p = vec3<f32>(dot(r0, h), dot(r1, h), dot(r2, h));
    out.clip = vec4<f32>(cam.proj.x * p.x, -cam.proj.y * p.y, cam.proj.z * p.z + cam.proj.w, p.z);
    out.item = item;
#if RGB DEPTH NORMAL SFLOW OFLOW
    out.p = p;
#endif
#if RGB NORMAL
    out.n = vec3<f32>(dot(r0.xyz, nrm.xyz), dot(r1.xyz, nrm.xyz), dot(r2.xyz, nrm.xyz));
#endif
#if SFLOW OFLOW
    out.q = vec3<f32>(dot(xf[b + 3u], h), dot(xf[b + 4u], h), dot(xf[b + 5u], h));
#endif
    return out;
}

#if RGB DEPTH NORMAL IDS SFLOW OFLOW
struct FsOut {
#if RGB
    @location(LOC_RGB) rgb: vec4<f32>,
#endif
#if DEPTH
    @location(LOC_DEPTH) depth: f32,
#endif
#if NORMAL
    @location(LOC_NORMAL) normal: vec4<f32>,
#endif
#if IDS
    @location(LOC_IDS) ids: vec2<u32>,
#endif
#if SFLOW
    @location(LOC_SFLOW) sflow: vec4<f32>,
#endif
#if OFLOW
    @location(LOC_OFLOW) oflow: vec2<f32>,
#endif
}

const PI: f32 = 3.14159265;

#if RGB
fn ggx_d(nh: f32, a: f32) -> f32 {
    let a2 = a * a;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d + 1e-7);
}

// Smith height-correlated visibility term V = G / (4 NL NV).
fn smith_v(nl: f32, nv: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    let gl = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    return 0.5 / (gv + gl + 1e-7);
}

fn fresnel(f0: vec3<f32>, vh: f32) -> vec3<f32> {
    let k = pow(1.0 - vh, 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * k;
}

// Radiance of the ambient sky/ground dome in direction d, blurred by `width`.
fn dome(d: vec3<f32>, width: f32) -> vec3<f32> {
    let t = smoothstep(-width, width, dot(d, cam.up.xyz));
    return mix(cam.ground.rgb, cam.sky.rgb, t);
}

// Analytic fit of the pre-integrated split-sum specular environment BRDF: (scale, bias) of F0.
fn env_brdf(nv: f32, roughness: f32) -> vec2<f32> {
    let c0 = vec4<f32>(-1.0, -0.0275, -0.572, 0.022);
    let c1 = vec4<f32>(1.0, 0.0425, 1.04, -0.04);
    let r = roughness * c0 + c1;
    let a = min(r.x * r.x, exp2(-9.28 * nv)) * r.x + r.y;
    return vec2<f32>(-1.04, 1.04) * a + r.zw;
}

fn aces(x: vec3<f32>) -> vec3<f32> {
    let y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return clamp(y, vec3<f32>(0.0), vec3<f32>(1.0));
}

#if SHADOW
fn shadow_factor(p: vec3<f32>, nl: f32) -> f32 {
    let s = cam.shadow * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(s.x * 0.5 + 0.5, 0.5 - s.y * 0.5);
    if (any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || s.z > 1.0) {
        return 1.0;
    }
    let bias = 0.0015 + 0.003 * (1.0 - nl);
    // One linearly filtered comparison: 2×2 percentage-closer filtering by the sampler.
    return textureSampleCompareLevel(shadow_map, shadow_sampler, uv, s.z - bias);
}
#endif

fn shade(m: Material, n: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let v = normalize(-p);
    let base = m.color.rgb;
    var radiance = vec3<f32>(0.0);
#if PBR
    let rough = clamp(m.roughness, 0.04, 1.0);
    let a = rough * rough;
    let metallic = clamp(m.metallic, 0.0, 1.0);
    let f0 = mix(vec3<f32>(0.04), base, metallic);
    let diffuse = base * (1.0 - metallic);
    let nv = max(dot(n, v), 1e-4);
#else
    let diffuse = base;
#endif
    let count = min(cam.counts.x, 8u);
    for (var i = 0u; i < count; i++) {
        let light = cam.lights[i];
        var l: vec3<f32>;
        var e: vec3<f32>;
        if (light.pos.w > 0.5) {
            let d = light.pos.xyz - p;
            let d2 = max(dot(d, d), 1e-4);
            l = d * inverseSqrt(d2);
            e = light.color.rgb / d2;
        } else {
            l = light.pos.xyz;
            e = light.color.rgb;
        }
        let nl = dot(n, l);
        if (nl <= 0.0) {
            continue;
        }
#if SHADOW
        if (i + 1u == cam.counts.y) {
            e *= shadow_factor(p, nl);
        }
#endif
#if PBR
        let hv = normalize(l + v);
        let nh = max(dot(n, hv), 0.0);
        let f = fresnel(f0, max(dot(v, hv), 0.0));
        let spec = f * (ggx_d(nh, a) * smith_v(nl, nv, a));
        let kd = (vec3<f32>(1.0) - f) * diffuse / PI;
        radiance += (kd + spec) * e * nl;
#else
        radiance += diffuse / PI * e * nl;
#endif
    }
#if PBR
    // Image-based ambient light from the sky/ground dome: irradiance for the diffuse part,
    // a roughness-blurred reflection with the split-sum BRDF for the specular part.
    let irradiance = dome(n, 1.0);
    let r = reflect(-v, n);
    let ab = env_brdf(nv, rough);
    let spec_env = dome(r, 0.05 + rough) * (f0 * ab.x + ab.y);
    radiance += diffuse * irradiance + spec_env;
#else
    radiance += diffuse * dome(n, 1.0);
#endif
    return aces(radiance * cam.up.w);
}
#endif

@fragment
fn fs_main(in: VsOut) -> FsOut {
    var out: FsOut;
#if RGB NORMAL
    var n = normalize(in.n);
    if (dot(n, in.p) > 0.0) {
        n = -n;
    }
#endif
#if RGB
    // The target is sRGB: the hardware encodes the tone-mapped linear value.
    out.rgb = vec4<f32>(shade(materials[in.item], n, in.p), 1.0);
#endif
#if DEPTH
    out.depth = in.p.z;
#endif
#if NORMAL
    out.normal = vec4<f32>(n, 0.0);
#endif
#if IDS
    let m = materials[in.item];
    out.ids = vec2<u32>(m.semantic, m.instance);
#endif
#if SFLOW
    out.sflow = vec4<f32>(in.p - in.q, 0.0);
#endif
#if OFLOW
    if (in.q.z > 1e-6) {
        let now = cam.pix.xy * in.p.xy / in.p.z;
        let before = cam.pix.xy * in.q.xy / in.q.z;
        out.oflow = now - before;
    } else {
        out.oflow = vec2<f32>(0.0);
    }
#endif
    return out;
}
#endif
