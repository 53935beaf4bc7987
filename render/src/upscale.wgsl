// Stretches the scene drawn at a lower internal resolution over its part of the frame, with
// bilinear filtering (in linear light: the sRGB texture decodes on sampling).
@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var bilinear: sampler;
struct Out { @builtin(position) pos: vec4<f32>, @location(0) uv: vec2<f32> };
@vertex fn vs(@builtin(vertex_index) i: u32) -> Out {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var o: Out;
    o.pos = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    o.uv = uv;
    return o;
}
@fragment fn fs(o: Out) -> @location(0) vec4<f32> {
    return textureSample(scene, bilinear, o.uv);
}
