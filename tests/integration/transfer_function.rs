//! Transfer functions: specs, ParaView JSON, the LUT lookup, and the
//! conservative max-alpha range query classification relies on.

use lacuna::tf::{TransferFunction, LUT_SIZE};
use lacuna::Error;

fn invalid(spec: &str, needle: &str) {
    match TransferFunction::parse(spec) {
        Err(e @ Error::Invalid { .. }) => assert!(e.to_string().contains(needle), "{spec}: '{e}' lacks '{needle}'"),
        other => panic!("{spec}: expected an invalid-TF error, got {other:?}"),
    }
}

/// Uniform numbers in [0, 1) from a seed (an LCG: the same every run).
fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[test]
fn specs_parse_into_the_documented_shapes() {
    let ramp = TransferFunction::parse("ramp:0.2:0.6").unwrap();
    assert_eq!(ramp.lookup(0.1)[3], 0.0);
    assert!((ramp.lookup(0.4)[3] - 0.5).abs() < 2e-3);
    assert_eq!(ramp.lookup(0.9)[3], 1.0);
    let band = TransferFunction::parse("band:0.3:0.5:0.25").unwrap();
    assert_eq!(band.lookup(0.2)[3], 0.0);
    assert_eq!(band.lookup(0.4)[3], 0.25);
    assert_eq!(band.lookup(0.7)[3], 0.0);
    let spike = TransferFunction::parse("spike:0.5:0.1").unwrap();
    assert!((spike.lookup(0.5)[3] - 1.0).abs() < 1e-2);
    assert_eq!(spike.lookup(0.6)[3], 0.0);
    assert_eq!(ramp.lut().len(), LUT_SIZE);
}

#[test]
fn malformed_specs_are_one_line_errors() {
    invalid("ramp:0.5", "expected ramp:LO:HI");
    invalid("ramp:0.6:0.2", "LO must be below HI");
    invalid("ramp:a:b", "'a' is not a finite number");
    invalid("ramp:0:1:2", "ALPHA must be in [0, 1]");
    invalid("band:0.5:0.4", "LO must not exceed HI");
    invalid("spike:0.5:0", "WIDTH must be > 0");
    invalid("spike:1.5:0.1", "CENTER must be in [0, 1]");
    invalid("ramp:nan:1", "not a finite number");
    invalid("wave:1:2", "expected ramp:LO:HI");
    invalid("", "expected ramp:LO:HI");
}

#[test]
fn max_alpha_is_conservative_over_every_interpolated_value() {
    let tfs = [
        "spike:0.5:0.0005",
        "band:0.31:0.3105:0.7",
        "ramp:0.9:0.95",
        "spike:0.0:0.001",
        "spike:1.0:0.001",
    ];
    let mut next = uniform(12345);
    for spec in tfs {
        let tf = TransferFunction::parse(spec).unwrap();
        for _ in 0..2000 {
            let (a, b) = (next(), next());
            let (lo, hi) = (a.min(b), a.max(b).min(a.min(b) + 0.01));
            let bound = tf.max_alpha(lo, hi);
            for k in 0..=200 {
                let v = lo + (hi - lo) * k as f32 / 200.0;
                assert!(
                    tf.lookup(v)[3] <= bound,
                    "{spec}: alpha {} at {v} exceeds max_alpha({lo}, {hi}) = {bound}",
                    tf.lookup(v)[3]
                );
            }
        }
        // A range that straddles the spike without a voxel value on it.
        assert!(tf.max_alpha(0.0, 1.0) > 0.0);
    }
    let clear = TransferFunction::parse("band:0.6:0.7").unwrap();
    assert_eq!(clear.max_alpha(0.0, 0.5), 0.0, "far from the band the range is empty");
    assert_eq!(clear.max_alpha(f32::INFINITY, f32::NEG_INFINITY), 0.0, "an empty range");
    assert!(clear.max_alpha(0.595, 0.599) > 0.0, "widened by one entry at the edge");
}

/// `visible` (a count of shown entries) answers `max_alpha > 0` for any
/// range: inside, on and beside LUT entries, empty, NaN and infinite bounds.
#[test]
fn visible_is_max_alpha_above_zero() {
    let mut next = uniform(777);
    let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.5, 1.5, 0.0, 1.0];
    for spec in [
        "band:0.4:0.41",
        "spike:0.0:0.001",
        "spike:1.0:0.001",
        "ramp:0.3:0.6",
        "band:0.6:0.7:0",
    ] {
        let tf = TransferFunction::parse(spec).unwrap();
        let (mut shown, mut hidden) = (0, 0);
        for n in 0..40000 {
            let pick = |x: f32, p: f32| match p {
                p if p < 0.05 => odd[(x * 7.0) as usize % odd.len()],
                p if p < 0.4 => (x * 1023.0).round() / 1023.0,
                _ => x * 1.2 - 0.1,
            };
            let (a, b) = (pick(next(), next()), pick(next(), next()));
            let (lo, hi) = if n % 5 == 0 { (a, b) } else { (a.min(b), a.max(b)) };
            let want = tf.max_alpha(lo, hi) > 0.0;
            assert_eq!(tf.visible(lo, hi), want, "{spec}: [{lo}, {hi}]");
            *if want { &mut shown } else { &mut hidden } += 1;
        }
        let all_clear = spec.ends_with(":0");
        assert!(
            hidden > 0 && (shown > 0) != all_clear,
            "{spec}: {shown} shown, {hidden} hidden"
        );
    }
}

#[test]
fn paraview_json_colormaps() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cmap.json");
    std::fs::write(
        &p,
        r#"[{"ColorSpace":"RGB","Name":"test","RGBPoints":[-100,0,0,1, 0,0,1,0, 100,1,0,0],"Points":[-100,0,0.5,0, 0,0,0.5,0, 100,0.8,0.5,0]}]"#,
    )
    .unwrap();
    let tf = TransferFunction::parse(p.to_str().unwrap()).unwrap();
    // x in [-100, 100] maps onto [0, 1].
    let mid = tf.lookup(0.5);
    assert!(mid[1] > 0.99 && mid[3] < 1e-3, "{mid:?}");
    let top = tf.lookup(1.0);
    assert!((top[0] - 1.0).abs() < 1e-6 && (top[3] - 0.8).abs() < 1e-6, "{top:?}");
    assert!((tf.lookup(0.75)[3] - 0.4).abs() < 1e-3);
    // Without opacity points: a linear ramp.
    std::fs::write(&p, r#"{"RGBPoints":[0,0,0,0, 1,1,1,1]}"#).unwrap();
    let tf = TransferFunction::parse(p.to_str().unwrap()).unwrap();
    assert!((tf.lookup(0.25)[3] - 0.25).abs() < 1e-3);

    for (text, needle) in [
        ("{not json", "invalid JSON"),
        (r#"{"Points":[0,0,0.5,0]}"#, "no 'RGBPoints'"),
        (r#"{"RGBPoints":[0,0,0]}"#, "groups of 4"),
        (r#"{"RGBPoints":[1,0,0,0, 0,1,1,1]}"#, "ascending"),
        (r#"{"RGBPoints":[0,0,0,0, 1,1,1,1],"Points":[0,2,0.5,0]}"#, "in [0, 1]"),
        (
            r#"{"RGBPoints":[0,5,0,0, 1,0,1,0]}"#,
            "'RGBPoints' colours must be in [0, 1]",
        ),
        (r#"{"RGBPoints":[0,0,0,0, 1,"a",1,1]}"#, "not a finite number"),
    ] {
        std::fs::write(&p, text).unwrap();
        match TransferFunction::parse(p.to_str().unwrap()) {
            Err(e @ Error::Format { .. }) => {
                assert!(e.to_string().contains(needle), "'{e}' lacks '{needle}'")
            }
            other => panic!("{text}: expected a format error, got {other:?}"),
        }
    }
    std::fs::write(
        &p,
        r#"{"RGBPoints":[0,0,0,0, 1,1,1,1],"Points":[0.5,0,0.5,0, 0,1,0.5,0]}"#,
    )
    .unwrap();
    let e = TransferFunction::parse(p.to_str().unwrap()).unwrap_err().to_string();
    assert!(e.contains("opacity 'Points' x values must be ascending"), "{e}");
    let missing = dir.path().join("missing.json");
    assert!(matches!(
        TransferFunction::parse(missing.to_str().unwrap()),
        Err(Error::Io { .. })
    ));
}

/// A colormap of many uneven points, with repeated x (steps), builds the
/// table a segment-by-segment scan of its points gives, entry for entry.
#[test]
fn a_colormap_of_many_points_is_interpolated_between_its_neighbours() {
    let n = 5000;
    let xs: Vec<f64> = (0..n).map(|i| ((i / 2) as f64).powf(1.5) - 300.0).collect();
    let rgb: Vec<f64> = (0..n)
        .flat_map(|i| {
            let t = i as f64;
            [
                xs[i],
                (t * 0.37).sin() * 0.5 + 0.5,
                (i % 3) as f64 / 2.0,
                (i % 7 == 0) as u8 as f64,
            ]
        })
        .collect();
    let op: Vec<f64> = (0..n / 10)
        .flat_map(|i| [xs[i * 10], ((i * 13) % 17) as f64 / 16.0, 0.5, 0.0])
        .collect();
    let json = format!(
        r#"{{"RGBPoints":[{}],"Points":[{}]}}"#,
        rgb.iter().map(f64::to_string).collect::<Vec<_>>().join(","),
        op.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
    );
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("many.json");
    std::fs::write(&p, json).unwrap();
    let tf = TransferFunction::parse(p.to_str().unwrap()).unwrap();
    // The scan: the first segment whose end is at or past x.
    let scan = |pts: &[f64], x: f64, c: usize| -> f64 {
        let g: Vec<&[f64]> = pts.chunks(4).collect();
        if x <= g[0][0] {
            return g[0][c];
        }
        for w in g.windows(2) {
            if x <= w[1][0] {
                let span = w[1][0] - w[0][0];
                let f = if span > 0.0 { (x - w[0][0]) / span } else { 1.0 };
                return w[0][c] + (w[1][c] - w[0][c]) * f;
            }
        }
        g[g.len() - 1][c]
    };
    let lut = tf.lut();
    let (x0, x1) = (xs[0], xs[n - 1]);
    for (i, entry) in lut.iter().enumerate() {
        let x = x0 + (x1 - x0) * (i as f32 / (lut.len() - 1) as f32) as f64;
        let want = [scan(&rgb, x, 1), scan(&rgb, x, 2), scan(&rgb, x, 3), scan(&op, x, 1)].map(|v| v as f32);
        assert_eq!(entry[..3], want[..3], "entry {i}");
        // from_lut may clamp alpha into [0, 1]; these are inside it.
        assert_eq!(entry[3], want[3], "entry {i}");
    }
}
