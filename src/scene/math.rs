//! The SPD generators' algebra, on glam's f64 types.
//!
//! The SPD writes matrices for row vectors (`v' = v·M`, translation in row 3,
//! `a·b` applies `a` first). Here they are glam's column-vector `DMat4`s, that
//! is the transposes: the SPD's row i is glam's column i, `v·M` is
//! `m.transform_point3(v)` (or `transform_vector3`), and `a·b` is `b * a`.
//! glam sums the products of a matrix-vector and a matrix-matrix product in
//! the SPD's order (only the two factors of each product swap, which is
//! exact), and its axis rotations have the SPD's entries, so every result is
//! bit for bit the one of the row-vector code. The exceptions, kept here as
//! explicit formulas, are `normalize` and `rotate_about`.

use glam::{DMat4, DVec3};

/// Unit vector along `a`; a zero vector stays zero.
///
/// Not glam's `normalize()` (NaN for a zero vector) nor `normalize_or_zero()`
/// (which also zeroes NaN, infinite and tiny vectors whose reciprocal length
/// overflows): the SPD's formula, `a * (1 / |a|)` when `|a| > 0`, else `a`.
pub fn normalize(a: DVec3) -> DVec3 {
    let l = a.length();
    if l > 0.0 {
        a * (1.0 / l)
    } else {
        a
    }
}

/// Rotation by `angle` radians about the unit vector `a`, with the SPD's
/// entries: glam's `from_axis_angle` computes the diagonal as
/// `a_i² (1 - cos) + cos` rather than `a_i² + (1 - a_i²) cos`, which rounds
/// differently.
pub fn rotate_about(a: DVec3, angle: f64) -> DMat4 {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    // The SPD's rows, as glam's columns.
    DMat4::from_cols_array_2d(&[
        [
            a.x * a.x + (1.0 - a.x * a.x) * c,
            a.x * a.y * t + a.z * s,
            a.x * a.z * t - a.y * s,
            0.0,
        ],
        [
            a.x * a.y * t - a.z * s,
            a.y * a.y + (1.0 - a.y * a.y) * c,
            a.y * a.z * t + a.x * s,
            0.0,
        ],
        [
            a.x * a.z * t + a.y * s,
            a.y * a.z * t - a.x * s,
            a.z * a.z + (1.0 - a.z * a.z) * c,
            0.0,
        ],
        [0.0, 0.0, 0.0, 1.0],
    ])
}
