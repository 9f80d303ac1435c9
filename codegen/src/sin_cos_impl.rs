/// `(sin x, cos x)` for the generated code: Cody–Waite reduction by π/2 (fdlibm's constants)
/// and fdlibm's minimax kernels on [−π/4, π/4], branch-free except for a fallback to the
/// standard library for |x| ≥ 2¹⁹·π/2 (or NaN). Error within about one ulp of the standard
/// library for the angles robots use; several times faster because both values share one
/// reduction and the code inlines.
#[inline(always)]
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() >= 823_549.0 {
        return x.sin_cos();
    }
    // n = round(x · 2/π) by the 1.5·2⁵² trick (exact for |x·2/π| < 2⁵¹).
    let shifted = x * core::f64::consts::FRAC_2_PI + 6_755_399_441_055_744.0;
    let n = shifted - 6_755_399_441_055_744.0;
    let quadrant = shifted.to_bits();
    // r = x − n·π/2 in three parts (π/2 = PIO2_1 + PIO2_2 + PIO2_2T, 33 + 33 + 53 bits).
    let r1 = x - n * 1.570_796_326_734_125_614_17;
    let w = n * 6.077_100_506_303_965_976_60e-11;
    let r2 = r1 - w;
    let w2 = n * 2.022_266_248_795_950_631_54e-21 - ((r1 - r2) - w);
    let r = r2 - w2;
    let z = r * r;
    // fdlibm __kernel_sin / __kernel_cos.
    let s = r
        + r * z
            * (-1.666_666_666_666_663_243_48e-01
                + z * (8.333_333_333_322_489_461_24e-03
                    + z * (-1.984_126_982_985_794_931_34e-04
                        + z * (2.755_731_370_707_006_767_89e-06
                            + z * (-2.505_076_025_340_686_341_95e-08
                                + z * 1.589_690_995_211_550_102_21e-10)))));
    let poly_c = z
        * z
        * (4.166_666_666_666_660_190_37e-02
            + z * (-1.388_888_888_887_410_957_49e-03
                + z * (2.480_158_728_947_672_941_78e-05
                    + z * (-2.755_731_435_139_066_330_35e-07
                        + z * (2.087_572_321_298_174_827_90e-09
                            + z * -1.135_964_755_778_819_482_65e-11)))));
    let hz = 0.5 * z;
    let one_minus_hz = 1.0 - hz;
    let c = one_minus_hz + (((1.0 - one_minus_hz) - hz) + poly_c);
    // Quadrant: swap on odd n, then flip signs (sin on quadrants 2, 3; cos on 1, 2).
    let odd = quadrant & 1 == 1;
    let (a, b) = if odd { (c, s) } else { (s, c) };
    let sign_a = (quadrant & 2) << 62;
    let sign_b = ((quadrant + 1) & 2) << 62;
    (
        f64::from_bits(a.to_bits() ^ sign_a),
        f64::from_bits(b.to_bits() ^ sign_b),
    )
}
