//! Additive CCD under tangential sliding: a point gliding over a triangle
//! at a constant small gap is not a hit, however long the slide (up to the
//! iteration cap's reach `l / (0.9 g)`), while the same slide with an
//! approach still is, and the reported time keeps the separation.

use sdrs_ipc::ccd::{AccdOptions, additive_ccd};
use sdrs_ipc::primitive::{PrimitiveKind, stencil_distance};

/// A large triangle in the plane z = 0 and a point `gap` above it.
fn stencil(gap: f64) -> [[f64; 3]; 4] {
    [
        [0.0, 0.0, gap],
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [0.0, 1.0, 0.0],
    ]
}

#[test]
fn sliding_at_a_small_gap_is_not_a_hit_and_approaching_is() {
    let opts = AccdOptions::default();
    for (gap, slide) in [(1e-4, 0.1), (1e-5, 0.02), (2e-5, 0.05)] {
        let x0 = stencil(gap);
        // The point slides by `slide` along x (0.9 g per iteration: the
        // former cap of 200 iterations reported a hit at t ≈ 180 g / slide).
        let dx = [[slide, 0.0, 0.0], [0.0; 3], [0.0; 3], [0.0; 3]];
        let t = additive_ccd(PrimitiveKind::PointTriangle, &x0, &dx, 0.0, 1.0, &opts);
        assert_eq!(t, None, "gap {gap}, slide {slide}: spurious hit at {t:?}");
        // Sliding while closing the gap: a hit, before contact, keeping a
        // fraction of the gap.
        let dx = [[slide, 0.0, -2.0 * gap], [0.0; 3], [0.0; 3], [0.0; 3]];
        let t = additive_ccd(PrimitiveKind::PointTriangle, &x0, &dx, 0.0, 1.0, &opts)
            .expect("approach must be a hit");
        assert!(t > 0.0 && t < 0.5, "gap {gap}: t = {t}");
        let at: [[f64; 3]; 4] =
            std::array::from_fn(|i| std::array::from_fn(|k| x0[i][k] + t * dx[i][k]));
        let d = stencil_distance(PrimitiveKind::PointTriangle, &at).0.sqrt();
        assert!(d >= 0.1 * gap * 0.999, "gap {gap}: distance {d} at t = {t}");
    }
}

#[test]
fn beyond_the_iteration_cap_a_slide_is_a_conservative_hit() {
    // 0.2 m at a 20 µm gap needs ~11 000 iterations: the cap (5000) ends
    // the advancement and reports the last safe time, not "no hit".
    let x0 = stencil(2e-5);
    let dx = [[0.2, 0.0, 0.0], [0.0; 3], [0.0; 3], [0.0; 3]];
    let t = additive_ccd(
        PrimitiveKind::PointTriangle,
        &x0,
        &dx,
        0.0,
        1.0,
        &AccdOptions::default(),
    )
    .expect("capped: a conservative hit");
    assert!((0.4..0.5).contains(&t), "t = {t}");
}
