//! Sphereflake: each sphere blooms nine children of a third of its radius.

use super::math::rotate_about;
use super::{view, Builder, Material, View};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    b.material(Material::new(DVec3::new(1.0, 0.75, 0.33), 0.8, 0.0, 0.0, 0.0, 1.0));
    let (x, y, z) = (12.0, 12.0, -0.5);
    b.polygon(vec![
        DVec3::new(x, y, z),
        DVec3::new(-x, y, z),
        DVec3::new(-x, -y, z),
        DVec3::new(x, -y, z),
    ]);
    b.material(Material::new(DVec3::new(1.0, 0.9, 0.7), 0.5, 0.5, 37.0, 0.0, 1.0));
    let set = directions();
    flake(b, &set, sf, DVec3::ZERO, 0.5, DVec3::Z, 1.0 / 3.0);
    (
        view(DVec3::new(2.1, 1.3, 1.7), DVec3::ZERO, DVec3::Z, 45.0, 0.01),
        vec![
            DVec3::new(4.0, 3.0, 2.0),
            DVec3::new(1.0, -4.0, 4.0),
            DVec3::new(-3.0, 1.0, 5.0),
        ],
    )
}

/// The nine child directions about +Z: three around a tilted trio, three times.
fn directions() -> [DVec3; 9] {
    let d = 1.0 / 2f64.sqrt();
    // glam's normalize(): a constant non-zero vector, times 1/length as the SPD does.
    let tilt = rotate_about(DVec3::new(1.0, -1.0, 0.0).normalize(), (2.0 / 6f64.sqrt()).asin());
    let trio =
        [DVec3::new(d, d, 0.0), DVec3::new(d, 0.0, -d), DVec3::new(0.0, d, -d)].map(|v| tilt.transform_vector3(v));
    let mut set = [DVec3::ZERO; 9];
    for s in 0..3 {
        let spin = DMat4::from_rotation_z(s as f64 * 2.0 * PI / 3.0);
        for v in 0..3 {
            set[s * 3 + v] = spin.transform_vector3(trio[v]);
        }
    }
    set
}

fn flake(b: &mut Builder, set: &[DVec3; 9], depth: u32, center: DVec3, radius: f64, dir: DVec3, ratio: f64) {
    b.sphere(center, radius);
    if depth == 0 {
        return;
    }
    // The current SPD's tolerance (>= 0.9999) for "direction is +-Z".
    let mx = if dir.z >= 0.9999 {
        DMat4::IDENTITY
    } else if dir.z <= -0.9999 {
        DMat4::from_rotation_y(PI)
    } else {
        // Not along Z, so the cross product is not zero and glam's
        // normalize() is the SPD's (times 1/length).
        rotate_about(DVec3::Z.cross(dir).normalize(), DVec3::Z.dot(dir).acos())
    };
    let s = radius * (1.0 + ratio);
    for v in set {
        let child = mx.transform_vector3(*v) * s + center;
        let child_dir = (child - center) * (1.0 / s);
        flake(b, set, depth - 1, child, radius * ratio, child_dir, ratio);
    }
}
