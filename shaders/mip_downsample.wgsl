// Builds one mip level of a 3D volume as the box average of the 8 texels below it.

@group(0) @binding(0) var src: texture_3d<f32>;
@group(0) @binding(1) var dst: texture_storage_3d<rgba8unorm, write>;

@compute @workgroup_size(4, 4, 4)
fn downsample(@builtin(global_invocation_id) id: vec3u) {
    let dims = textureDimensions(dst);
    if (any(id >= dims)) {
        return;
    }
    var sum = vec4f(0.0);
    for (var k = 0u; k < 8u; k++) {
        let o = vec3u(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
        sum += textureLoad(src, id * 2u + o, 0);
    }
    textureStore(dst, id, sum * 0.125);
}
