// Primary rays from RenderParams (orthographic or perspective), in voxel space.
#ifndef LACUNA_CAMERA_GLSL
#define LACUNA_CAMERA_GLSL

Ray camera_ray(uvec2 px) {
    precise vec3 p = params.base.xyz + (float(px.x) + 0.5) * params.du.xyz + (float(px.y) + 0.5) * params.dv.xyz;
    Ray r;
    if (params.eye_or_dir.w == 0.0) {
        r.org = p;
        r.dir = normalize(params.eye_or_dir.xyz);
    } else {
        r.org = params.eye_or_dir.xyz;
        r.dir = normalize(p - r.org);
    }
    return r;
}

#endif
