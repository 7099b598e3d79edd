//! How the CPU reference mixes a sample's channels (README, "Channels").

/// Channels' colours mixed as densities, as `mix_channels` in
/// `glsl/common/lattice.glsl`: opacity `1 - prod(1 - a_c)`, colour the
/// channels' weighted by `a_c`; one showing channel is itself.
pub fn mix_channels(colours: &[[f32; 4]]) -> [f32; 4] {
    let shown: Vec<&[f32; 4]> = colours.iter().filter(|c| c[3] > 0.0).collect();
    match shown.as_slice() {
        [] => [0.0; 4],
        [only] => **only,
        _ => {
            let (mut keep, mut sum, mut weight) = (1.0f32, [0f32; 3], 0f32);
            for c in shown {
                let a = c[3].min(1.0);
                keep *= 1.0 - a;
                for i in 0..3 {
                    sum[i] += a * c[i];
                }
                weight += a;
            }
            [sum[0] / weight, sum[1] / weight, sum[2] / weight, 1.0 - keep]
        }
    }
}
