//! The ray direction octants a frame's rays fall in. An octant distance map
//! computes its distances only for these (`accel::distance`): a frame from
//! outside the volume uses one to four of the eight, an orthographic frame
//! one.

use super::{FrameDesc, Rays};
use crate::error::Result;

/// A set of ray direction octants. Octant `o` has bit `a` set where its rays
/// run towards negative `a`, as the march counts it (`dir[a] < 0`; a zero
/// component counts as positive).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Octants(u8);

impl Octants {
    pub const ALL: Octants = Octants(0xff);
    pub const NONE: Octants = Octants(0);

    pub const fn from_bits(bits: u8) -> Octants {
        Octants(bits)
    }

    /// The set holding octant `o` (0 to 7) alone.
    pub fn one(o: u32) -> Octants {
        Octants(1 << (o & 7))
    }

    pub fn bits(self) -> u8 {
        self.0
    }

    pub fn has(self, o: u32) -> bool {
        o < 8 && self.0 >> o & 1 == 1
    }

    pub fn contains(self, other: Octants) -> bool {
        other.0 & !self.0 == 0
    }

    pub fn union(self, other: Octants) -> Octants {
        Octants(self.0 | other.0)
    }

    pub fn len(self) -> u32 {
        self.0.count_ones()
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The octants in increasing order.
    pub fn iter(self) -> impl Iterator<Item = u32> {
        (0..8).filter(move |&o| self.has(o))
    }

    /// The octants of `rays` over a `width` x `height` image, conservatively:
    /// a direction component within rounding of zero counts as both signs,
    /// so the set holds every octant the shaders can compute.
    pub fn of_rays(rays: &Rays, width: u32, height: u32) -> Octants {
        let d = |v: [f32; 3]| v.map(f64::from);
        let (base, du, dv, e) = (d(rays.base), d(rays.du), d(rays.dv), d(rays.eye_or_dir));
        // Per axis, the direction component over the image: constant for
        // orthographic rays, affine in the pixel for perspective ones, so
        // its extremes are at the image's corners.
        let corners = [
            (0.0, 0.0),
            (width as f64, 0.0),
            (0.0, height as f64),
            (width as f64, height as f64),
        ];
        let mut signs = [[false; 2]; 3]; // [positive, negative] per axis
        for (a, s) in signs.iter_mut().enumerate() {
            let (values, scale): (Vec<f64>, f64) = if rays.perspective {
                let values = corners
                    .iter()
                    .map(|&(u, v)| base[a] + u * du[a] + v * dv[a] - e[a])
                    .collect();
                let scale = base[a].abs() + (width as f64 * du[a]).abs() + (height as f64 * dv[a]).abs() + e[a].abs();
                (values, scale)
            } else {
                (vec![e[a]], e.iter().map(|c| c.abs()).fold(0.0, f64::max))
            };
            // f32 rounding of the shaders' sums and normalize: far wider
            // than their error, far narrower than a degree.
            let tol = 1e-5 * scale;
            s[0] = values.iter().any(|&c| c > -tol);
            s[1] = values.iter().any(|&c| c < tol);
        }
        let mut set = Octants::NONE;
        for o in 0..8u32 {
            if (0..3).all(|a| signs[a][(o >> a & 1) as usize]) {
                set = set.union(Octants::one(o));
            }
        }
        set
    }
}

impl std::fmt::Display for Octants {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self
            .iter()
            .map(|o| {
                (0..3)
                    .map(|a| if o >> a & 1 == 1 { '-' } else { '+' })
                    .zip(['x', 'y', 'z'])
                    .map(|(s, n)| format!("{s}{n}"))
                    .collect()
            })
            .collect();
        write!(f, "{}", names.join(" "))
    }
}

impl FrameDesc {
    /// The ray direction octants of this frame's rays through a volume of
    /// `dims` voxels with `spacing` (conservative: `Octants::of_rays`).
    pub fn octants(&self, dims: [u32; 3], spacing: [f32; 3]) -> Result<Octants> {
        let (w, h) = self.size();
        Ok(Octants::of_rays(&self.camera().rays(dims, spacing, w, h)?, w, h))
    }

    /// The octants of every frame in `frames`.
    pub fn octants_of<'a>(
        frames: impl IntoIterator<Item = &'a FrameDesc>,
        dims: [u32; 3],
        spacing: [f32; 3],
    ) -> Result<Octants> {
        frames
            .into_iter()
            .try_fold(Octants::NONE, |set, f| Ok(set.union(f.octants(dims, spacing)?)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthographic_rays_have_one_octant_unless_on_an_axis_plane() {
        let z = [0.0; 3];
        let r = Rays::orthographic(z, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, -0.2, 0.9]);
        assert_eq!(Octants::of_rays(&r, 8, 8), Octants::one(2));
        // A zero component: both signs along y.
        let r = Rays::orthographic(z, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-0.3, 0.0, 0.9]);
        assert_eq!(Octants::of_rays(&r, 8, 8), Octants::from_bits(0b0000_1010));
    }

    #[test]
    fn perspective_rays_take_every_corner_sign() {
        // Eye at the image plane's centre height, looking along +z: the image
        // spans both x and both y signs, z positive.
        let mut r = Rays::orthographic([-1.0, -1.0, 5.0], [0.25, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 0.0]);
        r.perspective = true;
        assert_eq!(Octants::of_rays(&r, 8, 8), Octants::from_bits(0b0000_1111));
        // The eye beside the image: x positive only.
        r.eye_or_dir = [-3.0, 0.0, 0.0];
        assert_eq!(Octants::of_rays(&r, 8, 8), Octants::from_bits(0b0000_0101));
    }

    #[test]
    fn names_and_sets() {
        let s = Octants::one(0).union(Octants::one(7));
        assert_eq!(s.to_string(), "+x+y+z -x-y-z");
        assert!(Octants::ALL.contains(s) && !s.contains(Octants::ALL));
        assert_eq!(s.len(), 2);
        assert_eq!(s.iter().collect::<Vec<_>>(), vec![0, 7]);
    }
}
