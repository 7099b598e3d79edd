//! Fractal mountain (Carpenter's midpoint displacement on a square grid, with
//! the SPD's original hash, kept for comparability) and four glass spheres.

use super::math::rotate_about;
use super::{view, Builder, Material, View};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;

const MOUNTAIN_NO: i64 = 21;
const CORNER: f64 = -1.0;
const WIDTH: f64 = 2.0;

pub(super) fn generate(b: &mut Builder, sf: u32) -> (View, Vec<DVec3>) {
    b.material(Material::new(DVec3::ONE, 0.1, 0.1, 6.7, 0.9, 1.5));
    spheres(b, DVec3::new(-0.8, 0.8, 1.0), 0.17);
    b.material(Material::new(DVec3::new(0.5, 0.45, 0.35), 1.0, 0.0, 0.0, 0.0, 0.0));
    let ratio = 2.0 / ((2f64).ln() / (2.2 - 1.0)).exp();
    let m = Mountain {
        sf,
        points: (1u32 << sf) as f64,
        roughness: (ratio * ratio - 1.0).sqrt(),
    };
    m.grow(b, 1 << sf, 0, 0, [0.0; 4]);
    (
        view(DVec3::new(-1.6, 1.6, 1.7), DVec3::ZERO, DVec3::Z, 45.0, 0.01),
        vec![DVec3::new(-100.0, -100.0, 100.0)],
    )
}

fn spheres(b: &mut Builder, center: DVec3, r: f64) {
    let top = DVec3::new(0.0, 0.0, r * 1.5f64.sqrt());
    b.sphere(center + top, r);
    // glam's normalize(): a constant non-zero vector, times 1/length as the SPD does.
    let tilted = rotate_about(DVec3::new(1.0, 1.0, 0.0).normalize(), (-1.0f64 / 3.0).acos()).transform_vector3(top);
    for i in 0..3 {
        let p = DMat4::from_rotation_z(i as f64 * 2.0 * PI / 3.0).transform_vector3(tilted);
        b.sphere(p + center, r);
    }
}

/// Numerical Recipes' gasdev on the SPD's small LCG; platform independent in i64.
fn gauss_rand(seed: i64) -> f64 {
    const M1: i64 = 134456;
    const IA1: i64 = 8121;
    const IC1: i64 = 28411;
    let mut ix2 = seed;
    loop {
        let ix1 = (IC1 + ix2 * IA1) % M1;
        ix2 = (IC1 + ix1 * IA1) % M1;
        let v1 = ix1 as f64 * 2.0 / M1 as f64 - 1.0;
        let v2 = ix2 as f64 * 2.0 / M1 as f64 - 1.0;
        let r = v1 * v1 + v2 * v2;
        if r < 1.0 {
            return v1 * (-2.0 * r.ln() / r).sqrt();
        }
    }
}

struct Mountain {
    sf: u32,
    points: f64,
    roughness: f64,
}

impl Mountain {
    /// The original ("faulty") SPD hash, as in the 1987 CG&A images.
    fn hash(&self, a: i64, b: i64) -> i64 {
        let c = self.sf as i64;
        ((a << (23 - c)) + (b << (15 - c)) + (a << (7 - c))) & 0xffff
    }

    fn rand(&self, a: i64, b: i64) -> f64 {
        gauss_rand(MOUNTAIN_NO + self.hash(a, b))
    }

    /// `z`: heights at the lower-left, lower-right, upper-right, upper-left corners.
    fn grow(&self, b: &mut Builder, width: i64, x: i64, y: i64, z: [f64; 4]) {
        if width == 1 {
            let lx = CORNER + x as f64 * WIDTH / self.points;
            let rx = CORNER + (x + 1) as f64 * WIDTH / self.points;
            let ly = CORNER + y as f64 * WIDTH / self.points;
            let uy = CORNER + (y + 1) as f64 * WIDTH / self.points;
            let corner = [
                DVec3::new(lx, ly, z[0]),
                DVec3::new(rx, ly, z[1]),
                DVec3::new(rx, uy, z[2]),
                DVec3::new(lx, uy, z[3]),
            ];
            for tri in 0..2 {
                b.polygon((0..3).map(|v| corner[(v + tri * 2) % 4]).collect());
            }
            return;
        }
        let half = width >> 1;
        let rise = half as f64 * WIDTH / self.points * self.roughness;
        let lower = (z[0] + z[1]) / 2.0 + rise * self.rand(x + half, y);
        let right = (z[1] + z[2]) / 2.0 + rise * self.rand(x + width, y + half);
        let upper = (z[2] + z[3]) / 2.0 + rise * self.rand(x + half, y + width);
        let left = (z[3] + z[0]) / 2.0 + rise * self.rand(x, y + half);
        // The SPD's literal (not quite sqrt 2), for the same heights.
        #[allow(clippy::approx_constant)]
        let centre_gain = 1.4142136;
        let middle = (z[0] + z[1] + z[2] + z[3]) / 4.0 + centre_gain * rise * self.rand(x + half, y + half);
        self.grow(b, half, x, y, [z[0], lower, middle, left]);
        self.grow(b, half, x + half, y, [lower, z[1], right, middle]);
        self.grow(b, half, x + half, y + half, [middle, right, z[2], upper]);
        self.grow(b, half, x, y + half, [left, middle, upper, z[3]]);
    }
}
