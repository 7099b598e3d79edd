//! Tree: Aono & Kunii's branching tree of cones with spheres at the joints,
//! standing on a field.

use super::math::{Axis, Mat4, V3};
use super::{view, Builder, Material, View};
use std::f64::consts::PI;

const WIDTH_HEIGHT: f64 = 0.15;
const DIAMETER: f64 = 0.67;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<V3>) {
    b.material(Material::new([0.2, 0.7, 0.2], 1.0, 0.0, 0.0, 0.0, 0.0));
    b.polygon(vec![
        [50.0, 50.0, 0.0],
        [-50.0, 50.0, 0.0],
        [-50.0, -50.0, 0.0],
        [50.0, -50.0, 0.0],
    ]);
    b.material(Material::new([0.55, 0.4, 0.2], 1.0, 0.0, 0.0, 0.0, 0.0));
    let branch = |angle: f64, divergence: f64, contraction: f64| {
        let r = Mat4::rotate(Axis::X, angle * PI / 180.0).then(&Mat4::rotate(Axis::Z, divergence * PI / 180.0));
        let mut st = Mat4::identity();
        for i in 0..3 {
            st.0[i][i] = contraction;
        }
        st.0[3][2] = 1.0;
        r.then(&st)
    };
    let children = [branch(40.0, 90.0, 0.65), branch(25.0, 140.0 + 90.0, 0.70)];
    grow(b, &children, &Mat4::identity(), 1.0, sf);
    (
        view([4.5, 0.4, 2.0], [0.0, 0.0, 1.5], [0.0, 0.0, 1.0], 45.0, 1.0),
        vec![
            [-5.0, 5.0, 50.0],
            [30.0, -30.0, 30.0],
            [-40.0, -30.0, 20.0],
            [10.0, 30.0, 40.0],
            [-30.0, 40.0, 10.0],
            [50.0, 25.0, 20.0],
            [-10.0, -60.0, 30.0],
        ],
    )
}

fn grow(b: &mut Builder, children: &[Mat4; 2], m: &Mat4, scale: f64, depth: u32) {
    let base = m.point([0.0; 3]);
    let apex = m.point([0.0, 0.0, 1.0]);
    let r = scale * WIDTH_HEIGHT;
    b.cone(base, r, apex, r * DIAMETER);
    b.sphere(apex, r * DIAMETER);
    if depth > 0 {
        for c in children {
            grow(b, children, &c.then(m), scale * DIAMETER, depth - 1);
        }
    }
}
