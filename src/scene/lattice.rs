//! Lattice: shiny spheres on a cubic lattice joined by matte cylinders.

use super::{view, Builder, Material, View};
use glam::{DVec3, UVec3};

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    let n = sf as f64;
    let (r1, r2) = (0.25 / n, 1.0 / 16.0 / n);
    let delta = r1 * (1.0 - (r2 / r1).sqrt()) * 0.99;
    let inv = 1.0 / n;
    let sphere = Material::new(DVec3::splat(0.9), 0.5, 0.5, 37.0, 0.0, 0.0);
    let rods = [
        DVec3::new(0.9, 0.1, 0.1),
        DVec3::new(0.1, 0.9, 0.1),
        DVec3::new(0.1, 0.1, 0.9),
    ]
    .map(|c| Material::new(c, 0.99, 0.0, 0.0, 0.0, 0.0));
    for x in 0..=sf {
        for y in 0..=sf {
            for z in 0..=sf {
                let p = UVec3::new(x, y, z).as_dvec3() / n;
                b.material(sphere);
                b.sphere(p, r1);
                for (axis, i) in [x, y, z].into_iter().enumerate() {
                    if i != sf {
                        b.material(rods[axis]);
                        let (mut a, mut c) = (p, p);
                        a[axis] += delta;
                        c[axis] += inv - delta;
                        b.cone(a, r2, c, r2);
                    }
                }
            }
        }
    }
    let mid = ((sf >> 1) as f64 + 0.5) * inv;
    let lz = 1.0 / (2 * sf) as f64;
    (
        view(
            DVec3::new(mid, 1.0, 1.0 - lz),
            DVec3::new(mid, -1.0, -1.0 - lz),
            DVec3::new(0.2, 1.0, 0.0),
            60.0,
            0.0,
        ),
        vec![
            DVec3::new(2.0, 0.5, 0.5),
            DVec3::new(-1.0, 0.5, 0.5),
            DVec3::new(0.5, 2.0, 0.5),
            DVec3::new(0.5, -1.0, 0.5),
            DVec3::new(0.5, 0.5, 2.0),
            DVec3::new(0.5, 0.5, -1.0),
        ],
    )
}
