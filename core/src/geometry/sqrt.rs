//! The square root of the hot loops: correctly rounded with and without the `std`
//! feature, so maps and renders are the same bits either way.
//!
//! With `std` it is `f32::sqrt`, an intrinsic the compiler turns into vector instructions
//! (a render tests eight rays at a time); without, `libm::sqrtf`, which on x86-64 is a
//! scalar `sqrtss` in inline assembly: the compiler cannot widen it, and in AVX code each
//! one costs a switch of the vector state (a render took 9x longer).

/// `sqrt(x)`, correctly rounded (IEEE 754), NaN below zero.
#[inline(always)]
pub(crate) fn sqrt(x: f32) -> f32 {
    #[cfg(feature = "std")]
    {
        x.sqrt()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sqrtf(x)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    /// Both square roots agree bit for bit on every 97th positive float and on the edges.
    #[test]
    fn std_and_libm_agree() {
        for bits in (0..0x7f80_0000u32)
            .step_by(97)
            .chain([0, 1, 0x7f7f_ffff, 0x7f80_0000])
        {
            let x = f32::from_bits(bits);
            assert_eq!(
                std::primitive::f32::sqrt(x).to_bits(),
                libm::sqrtf(x).to_bits(),
                "{x}"
            );
        }
        assert!(super::sqrt(-1.0).is_nan());
    }
}
