//! Gears: SF^3 meshing gears (concave 144-gon faces and quad sides) over a
//! reflective ground; some gears are transparent.

use super::{view, Builder, Material, View};
use glam::{DMat4, DVec3, UVec3};
use std::f64::consts::PI;

const TEETH: usize = 36;
const OUTER: f64 = 0.995;
const INNER: f64 = 0.9;
const EDGE_DIFF: f64 = 1.0 - INNER;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    b.material(Material::new(DVec3::new(1.0, 0.85, 0.7), 0.3, 0.6, 37.0, 0.0, 0.0));
    b.polygon(vec![
        DVec3::new(2.0, 2.0, 0.0),
        DVec3::new(-2.0, 2.0, 0.0),
        DVec3::new(-2.0, -2.0, 0.0),
        DVec3::new(2.0, -2.0, 0.0),
    ]);
    let n = sf as f64;
    let radius = 1.0 / (n - (n - 1.0) * EDGE_DIFF / 2.0);
    let zero = DVec3::new(-1.0 + radius, -1.0 + radius, 1.0);
    let step = DVec3::new(radius * (2.0 - EDGE_DIFF), radius * (2.0 - EDGE_DIFF), -1.0 / n);
    let thickness = (0.1f64).min(1.0 / (2.0 * n));
    for iz in 0..sf {
        for iy in 0..sf {
            for ix in 0..sf {
                let center = zero + UVec3::new(ix, iy, iz).as_dvec3() * step;
                let frac = |v: f64| v - v.floor();
                let mut color = DVec3::new(
                    0.01 + frac((ix * 3 + iy * 2 + iz + 1) as f64 * 5.0 / 7.0),
                    0.01 + frac((iy * 3 + iz * 2 + ix + 1) as f64 * 3.0 / 7.0),
                    0.01 + frac((iz * 3 + ix * 2 + iy + 1) as f64 * 2.0 / 7.0),
                );
                // f64::max in this order, not glam's max_element (x max (y max z)).
                let m = color.x.max(color.y).max(color.z);
                color /= m;
                if (ix * 4 + iy * 2 + iz) % 5 == 0 {
                    b.material(Material::new(color, 0.2, 0.0, 0.0, 0.8, 1.1));
                } else {
                    b.material(Material::new(color, 1.0, 0.0, 0.0, 0.0, 0.0));
                }
                let angle = PI * ((ix + iy + iz) % 2) as f64 / TEETH as f64;
                gear(b, center, angle, OUTER * radius, (1.0 - EDGE_DIFF) * radius, thickness);
            }
        }
    }
    (
        view(DVec3::new(-1.1, -2.1, 2.6), DVec3::ZERO, DVec3::Z, 45.0, 1.0),
        vec![
            DVec3::new(2.0, 4.0, 4.0),
            DVec3::new(-2.0, 4.0, 3.0),
            DVec3::new(2.0, -2.5, 2.5),
            DVec3::new(-1.0, -4.0, 2.0),
            DVec3::new(-1.111, -2.121, 2.626),
        ],
    )
}

/// The four outline points of one tooth.
fn tooth(gear_angle: f64, tooth_angle: f64, center: DVec3, outer: DVec3, inner: DVec3) -> [DVec3; 4] {
    let at = |a: f64, p: DVec3| DMat4::from_rotation_z(gear_angle + a * tooth_angle).transform_vector3(p) + center;
    [at(-0.19, outer), at(0.19, outer), at(0.3, inner), at(0.7, inner)]
}

fn gear(b: &mut Builder, center: DVec3, offset: f64, outer_r: f64, inner_r: f64, thickness: f64) {
    let tooth_angle = 2.0 * PI / TEETH as f64;
    let outline = |sign: f64, z: f64| -> Vec<DVec3> {
        (0..TEETH)
            .flat_map(|t| {
                let a = offset + sign * 2.0 * PI * t as f64 / TEETH as f64;
                tooth(
                    a,
                    sign * tooth_angle,
                    center,
                    DVec3::new(outer_r, 0.0, z),
                    DVec3::new(inner_r, 0.0, z),
                )
            })
            .collect()
    };
    let top = outline(1.0, 0.0);
    b.polygon(top.clone());
    for i in 0..top.len() {
        let (p, q) = (top[i], top[(i + 1) % top.len()]);
        b.polygon(vec![p, p.with_z(p.z - thickness), q.with_z(q.z - thickness), q]);
    }
    b.polygon(outline(-1.0, -thickness));
}
