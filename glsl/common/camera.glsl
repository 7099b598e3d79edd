// Primary rays from RenderParams (orthographic or perspective), in voxel space.
#ifndef LACUNA_CAMERA_GLSL
#define LACUNA_CAMERA_GLSL

Ray camera_ray(uvec2 px) {
    precise vec3 p = params.base + (float(px.x) + 0.5) * params.du + (float(px.y) + 0.5) * params.dv;
    Ray r;
    if (params.perspective == 0u) {
        r.org = p;
        r.dir = normalize(params.eye_or_dir);
    } else {
        r.org = params.eye_or_dir;
        r.dir = normalize(p - r.org);
    }
    return r;
}

#endif
