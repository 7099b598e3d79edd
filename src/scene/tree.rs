//! Tree: Aono & Kunii's branching tree of cones with spheres at the joints,
//! standing on a field.

use super::{view, Builder, Material, View};
use glam::{DMat4, DVec3, DVec4};
use std::f64::consts::PI;

const WIDTH_HEIGHT: f64 = 0.15;
const DIAMETER: f64 = 0.67;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    b.material(Material::new(DVec3::new(0.2, 0.7, 0.2), 1.0, 0.0, 0.0, 0.0, 0.0));
    b.polygon(vec![
        DVec3::new(50.0, 50.0, 0.0),
        DVec3::new(-50.0, 50.0, 0.0),
        DVec3::new(-50.0, -50.0, 0.0),
        DVec3::new(50.0, -50.0, 0.0),
    ]);
    b.material(Material::new(DVec3::new(0.55, 0.4, 0.2), 1.0, 0.0, 0.0, 0.0, 0.0));
    // The SPD's row-vector products `a·b` (a first) are glam's `b * a`.
    let branch = |angle: f64, divergence: f64, contraction: f64| {
        let r = DMat4::from_rotation_z(divergence * PI / 180.0) * DMat4::from_rotation_x(angle * PI / 180.0);
        // Scale by `contraction`, then move up by 1 along z, entries as
        // written (not a product of a scale and a translation).
        let st = DMat4::from_cols(
            DVec4::new(contraction, 0.0, 0.0, 0.0),
            DVec4::new(0.0, contraction, 0.0, 0.0),
            DVec4::new(0.0, 0.0, contraction, 0.0),
            DVec4::new(0.0, 0.0, 1.0, 1.0),
        );
        st * r
    };
    let children = [branch(40.0, 90.0, 0.65), branch(25.0, 140.0 + 90.0, 0.70)];
    grow(b, &children, &DMat4::IDENTITY, 1.0, sf);
    (
        view(
            DVec3::new(4.5, 0.4, 2.0),
            DVec3::new(0.0, 0.0, 1.5),
            DVec3::Z,
            45.0,
            1.0,
        ),
        vec![
            DVec3::new(-5.0, 5.0, 50.0),
            DVec3::new(30.0, -30.0, 30.0),
            DVec3::new(-40.0, -30.0, 20.0),
            DVec3::new(10.0, 30.0, 40.0),
            DVec3::new(-30.0, 40.0, 10.0),
            DVec3::new(50.0, 25.0, 20.0),
            DVec3::new(-10.0, -60.0, 30.0),
        ],
    )
}

fn grow(b: &mut Builder, children: &[DMat4; 2], m: &DMat4, scale: f64, depth: u32) {
    let base = m.transform_point3(DVec3::ZERO);
    let apex = m.transform_point3(DVec3::Z);
    let r = scale * WIDTH_HEIGHT;
    b.cone(base, r, apex, r * DIAMETER);
    b.sphere(apex, r * DIAMETER);
    if depth > 0 {
        for c in children {
            grow(b, children, &(*m * *c), scale * DIAMETER, depth - 1);
        }
    }
}
