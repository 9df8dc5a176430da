// Shadow-map pass: depth only, orthographic from the first directional light.

// Per item: 3 rows of the affine map from the item frame to the light's clip space.
@group(0) @binding(0) var<storage, read> lxf: array<vec4<f32>>;

@vertex
fn vs_shadow(@location(0) pos: vec3<f32>, @location(2) item: u32) -> @builtin(position) vec4<f32> {
    let b = item * 3u;
    let h = vec4<f32>(pos, 1.0);
    return vec4<f32>(dot(lxf[b], h), dot(lxf[b + 1u], h), dot(lxf[b + 2u], h), 1.0);
}
