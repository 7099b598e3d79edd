//! Rings: a pyramid of objects made of six pentagonal rings of spheres and
//! cylinders (the edge midpoints of a dodecahedron), in front of a wall.

use super::{view, Builder, Material, View};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    let radius = 0.07412;
    let spread = 1.0 / (PI / 8.0).sin();
    let (y_diff, xz_diff) = (spread, 1.0);
    let from = DVec3::new(-1.0, -spread, 0.5);
    b.material(Material::new(DVec3::ONE, 1.0, 0.0, 0.0, 0.0, 0.0));
    let wy = y_diff * (sf + 1) as f64;
    let wxz = 1.01 * (wy - from.y) * (PI / 8.0).tan();
    b.polygon(vec![
        DVec3::new(wxz + from.x, wy, wxz + from.z),
        DVec3::new(-wxz + from.x, wy, wxz + from.z),
        DVec3::new(-wxz + from.x, wy, -wxz + from.z),
        DVec3::new(wxz + from.x, wy, -wxz + from.z),
    ]);
    let colors = [
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(1.0, 1.0, 0.0),
    ];
    let dodec = dodecahedron_rings(radius);
    for depth in 0..sf {
        for oz in 0..=depth {
            for ox in 0..=depth {
                let offset = DVec3::new(
                    xz_diff * (2 * ox) as f64 - xz_diff * depth as f64,
                    y_diff * (depth + 1) as f64,
                    xz_diff * (2 * oz) as f64 - xz_diff * depth as f64,
                );
                for e in 0..30 {
                    let prev = if e % 5 == 0 {
                        b.material(Material::new(colors[e / 5], 0.5, 0.2, 37.0, 0.0, 0.0));
                        e + 4
                    } else {
                        e - 1
                    };
                    let base = dodec[e] + offset;
                    b.cone(base, radius, dodec[prev] + offset, radius);
                    b.sphere(base, radius);
                }
            }
        }
    }
    (
        view(from, DVec3::new(from.x, from.y + 1.0, from.z), DVec3::Z, 45.0, 1.0),
        vec![
            DVec3::new(3.0, -spread, 3.0),
            DVec3::new(-4.0, -spread, 1.0),
            DVec3::new(2.0, -spread, -4.0),
        ],
    )
}

/// Six pentagons of five points each, scaled to fit a unit sphere.
fn dodecahedron_rings(minor_radius: f64) -> [DVec3; 30] {
    let s = 1.0 / (1.0 + minor_radius);
    let mut v = [DVec3::ZERO; 30];
    for (i, p) in v.iter_mut().take(5).enumerate() {
        let a = i as f64 * 2.0 * PI / 5.0;
        *p = DVec3::new(s * a.cos(), s * a.sin(), 0.0);
    }
    let x = DMat4::from_rotation_x(2.0 * ((PI / 3.0).cos() / (PI / 5.0).sin()).acos());
    for pent in 1..6 {
        let z = DMat4::from_rotation_z(PI * (2.0 * (pent - 1) as f64 + 1.0) / 5.0);
        for i in 0..5 {
            v[5 * pent + i] = z.transform_point3(x.transform_point3(v[i]));
        }
    }
    v
}
