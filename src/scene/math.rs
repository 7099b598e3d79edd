//! The little vector and matrix algebra the SPD generators need, in f64 and
//! with the SPD's conventions: row vectors (`v' = v·M`), so `mul(a, b)`
//! applies `a` first.

pub type V3 = [f64; 3];

pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn length(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// Unit vector along `a`; a zero vector stays zero.
pub fn normalize(a: V3) -> V3 {
    let l = length(a);
    if l > 0.0 {
        scale(a, 1.0 / l)
    } else {
        a
    }
}

/// 4x4 matrix, row-vector convention (translation in row 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat4(pub [[f64; 4]; 4]);

pub enum Axis {
    X,
    Y,
    Z,
}

impl Mat4 {
    pub fn identity() -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        Mat4(m)
    }

    /// Rotation by `angle` radians about a coordinate axis.
    pub fn rotate(axis: Axis, angle: f64) -> Mat4 {
        let (s, c) = angle.sin_cos();
        let mut m = Mat4::identity().0;
        let (i, j) = match axis {
            Axis::X => (1, 2),
            Axis::Y => (2, 0),
            Axis::Z => (0, 1),
        };
        m[i][i] = c;
        m[j][j] = c;
        m[i][j] = s;
        m[j][i] = -s;
        Mat4(m)
    }

    /// Rotation by `angle` radians about the unit vector `a`.
    pub fn rotate_about(a: V3, angle: f64) -> Mat4 {
        let (s, c) = angle.sin_cos();
        let t = 1.0 - c;
        Mat4([
            [
                a[0] * a[0] + (1.0 - a[0] * a[0]) * c,
                a[0] * a[1] * t + a[2] * s,
                a[0] * a[2] * t - a[1] * s,
                0.0,
            ],
            [
                a[0] * a[1] * t - a[2] * s,
                a[1] * a[1] + (1.0 - a[1] * a[1]) * c,
                a[1] * a[2] * t + a[0] * s,
                0.0,
            ],
            [
                a[0] * a[2] * t + a[1] * s,
                a[1] * a[2] * t - a[0] * s,
                a[2] * a[2] + (1.0 - a[2] * a[2]) * c,
                0.0,
            ],
            [0.0, 0.0, 0.0, 1.0],
        ])
    }

    /// `self` then `other`.
    pub fn then(&self, other: &Mat4) -> Mat4 {
        let (a, b) = (&self.0, &other.0);
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] + a[i][3] * b[3][j];
            }
        }
        Mat4(m)
    }

    pub fn point(&self, v: V3) -> V3 {
        let m = &self.0;
        [
            v[0] * m[0][0] + v[1] * m[1][0] + v[2] * m[2][0] + m[3][0],
            v[0] * m[0][1] + v[1] * m[1][1] + v[2] * m[2][1] + m[3][1],
            v[0] * m[0][2] + v[1] * m[1][2] + v[2] * m[2][2] + m[3][2],
        ]
    }

    pub fn vector(&self, v: V3) -> V3 {
        let m = &self.0;
        [
            v[0] * m[0][0] + v[1] * m[1][0] + v[2] * m[2][0],
            v[0] * m[0][1] + v[1] * m[1][1] + v[2] * m[2][1],
            v[0] * m[0][2] + v[1] * m[1][2] + v[2] * m[2][2],
        ]
    }
}
