//! Sphereflake: each sphere blooms nine children of a third of its radius.

use super::math::{add, cross, dot, normalize, scale, sub, Axis, Mat4, V3};
use super::{view, Builder, Material, View};
use std::f64::consts::PI;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<V3>) {
    b.material(Material::new([1.0, 0.75, 0.33], 0.8, 0.0, 0.0, 0.0, 1.0));
    let (x, y, z) = (12.0, 12.0, -0.5);
    b.polygon(vec![[x, y, z], [-x, y, z], [-x, -y, z], [x, -y, z]]);
    b.material(Material::new([1.0, 0.9, 0.7], 0.5, 0.5, 37.0, 0.0, 1.0));
    let set = directions();
    flake(b, &set, sf, [0.0, 0.0, 0.0], 0.5, [0.0, 0.0, 1.0], 1.0 / 3.0);
    (
        view([2.1, 1.3, 1.7], [0.0; 3], [0.0, 0.0, 1.0], 45.0, 0.01),
        vec![[4.0, 3.0, 2.0], [1.0, -4.0, 4.0], [-3.0, 1.0, 5.0]],
    )
}

/// The nine child directions about +Z: three around a tilted trio, three times.
fn directions() -> [V3; 9] {
    let d = 1.0 / 2f64.sqrt();
    let tilt = Mat4::rotate_about(normalize([1.0, -1.0, 0.0]), (2.0 / 6f64.sqrt()).asin());
    let trio = [[d, d, 0.0], [d, 0.0, -d], [0.0, d, -d]].map(|v| tilt.vector(v));
    let mut set = [[0.0; 3]; 9];
    for s in 0..3 {
        let spin = Mat4::rotate(Axis::Z, s as f64 * 2.0 * PI / 3.0);
        for v in 0..3 {
            set[s * 3 + v] = spin.vector(trio[v]);
        }
    }
    set
}

fn flake(b: &mut Builder, set: &[V3; 9], depth: u32, center: V3, radius: f64, dir: V3, ratio: f64) {
    b.sphere(center, radius);
    if depth == 0 {
        return;
    }
    // The current SPD's tolerance (>= 0.9999) for "direction is +-Z".
    let mx = if dir[2] >= 0.9999 {
        Mat4::identity()
    } else if dir[2] <= -0.9999 {
        Mat4::rotate(Axis::Y, PI)
    } else {
        let z = [0.0, 0.0, 1.0];
        Mat4::rotate_about(normalize(cross(z, dir)), dot(z, dir).acos())
    };
    let s = radius * (1.0 + ratio);
    for v in set {
        let child = add(scale(mx.vector(*v), s), center);
        let child_dir = scale(sub(child, center), 1.0 / s);
        flake(b, set, depth - 1, child, radius * ratio, child_dir, ratio);
    }
}
