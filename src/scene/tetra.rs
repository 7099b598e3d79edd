//! Tetra: a recursive tetrahedral pyramid (Sierpinski), 4^SF triangles.

use super::{view, Builder, Material, View};
use glam::DVec3;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    b.material(Material::new(DVec3::new(1.0, 0.2, 0.2), 1.0, 0.0, 0.0, 0.0, 0.0));
    tetra(b, sf, DVec3::ZERO, 1.0);
    (
        view(
            DVec3::new(1.022846, -3.177154, -2.174512),
            DVec3::new(-0.004103, -0.004103, 0.216539),
            DVec3::new(-0.816497, -0.816497, 0.816497),
            45.0,
            1.0,
        ),
        vec![DVec3::new(2.0, -18.0, -5.0)],
    )
}

/// The cube corners c + w*(x,y,z) with x*y*z = +1, in the SPD's order.
fn corners(c: DVec3, w: f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(4);
    for x in [-1.0, 1.0] {
        for y in [-1.0, 1.0] {
            for z in [-1.0, 1.0] {
                if x * y * z == 1.0 {
                    out.push(c + DVec3::new(x, y, z) * w);
                }
            }
        }
    }
    out
}

fn tetra(b: &mut Builder, depth: u32, c: DVec3, w: f64) {
    if depth <= 1 {
        let p = corners(c, w);
        for face in 0..4 {
            let mut order = [face, (face + 1) % 4, (face + 2) % 4];
            if face % 2 == 1 {
                order.swap(0, 2);
            }
            b.polygon(order.iter().map(|&i| p[i]).collect());
        }
    } else {
        for sub in corners(c, w / 2.0) {
            tetra(b, depth - 1, sub, w / 2.0);
        }
    }
}
