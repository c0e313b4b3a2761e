//! 16-bit error codes: the bitree's per-sample error, stored in two bytes as an
//! upper bound, with an exact tie-break at the threshold.
//!
//! Paper `001_49f2c365e8c41172.txt` keeps one error per split point of the
//! bitree; the papers store it as a float. Stored as `f32` it doubles the
//! memory of a bitree over the `f32` grid it describes (4 more bytes per
//! sample) and it is the array the extraction walk reads at random. Here each
//! error is stored as a `u16` *code*: the 31 value bits of the non-negative
//! `f32` error (sign bit 0) rounded **up** to their top 16 bits, i.e. 8
//! exponent bits and 8 mantissa bits (relative step 2⁻⁸ ≈ 0.4 %), so that
//!
//! * `decode(encode_up(e)) ≥ e` (never understated),
//! * `encode_up` is monotone, so the max of codes is the code of the max and the
//!   bitree's monotone error survives quantisation exactly,
//! * `+∞` (a triangle straddling the grid's border: always split) is the code
//!   [`INFINITE`] and decodes to `+∞`.
//!
//! # Deciding a split exactly
//! Extraction splits a split point `m` iff its exact error (the `f32` rounded up
//! from the `f64` computation, as before quantisation) exceeds the threshold
//! `E`. A [`SplitRule`] compares codes: a code at most `floor(E)` (the largest
//! code not above `E`) never splits, a code two or more above always does, and
//! only the code just above `floor(E)` is ambiguous — and only when `E` itself
//! is not a code value (thresholds with at most 9 significant bits, such as
//! 0.5, 1, 2, 2.5, 5, 10, 20, 50 m, never are). Those few split points are
//! settled by recomputing their exact own error ([`crate::Bitree`] does this),
//! so the extracted mesh is exactly the mesh of the unquantised errors, with
//! half the memory.
//!
//! # Runtime
//! `O(1)` per code.

/// The code of `+∞`: "always split".
pub const INFINITE: u16 = 0xFF00;

/// The smallest code whose value is at least `e` (non-negative; `+∞` gives
/// [`INFINITE`]). NaN is not an error value and is treated as `+∞`.
#[inline]
pub fn encode_up(e: f32) -> u16 {
    if e.is_nan() {
        return INFINITE;
    }
    let bits = e.max(0.0).to_bits();
    // bits ≤ 0x7F80_0000 (+∞), so the sum fits and the result is ≤ 0xFF00.
    ((bits + 0x7FFF) >> 15) as u16
}

/// The error value of a code: an upper bound of every error it encodes.
#[inline]
pub fn decode(code: u16) -> f32 {
    f32::from_bits(u32::from(code.min(INFINITE)) << 15)
}

/// The largest `f32` not above `e`: for every `f32` value `x`, `x > e` ⇔
/// `x > threshold_f32(e)`.
#[inline]
pub fn threshold_f32(e: f64) -> f32 {
    let f = e as f32;
    if f as f64 > e {
        f.next_down()
    } else {
        f
    }
}

/// How a threshold `E` decides splits on codes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitRule {
    /// Codes at most this never split.
    pub floor: u16,
    /// Whether the code `floor + 1` needs the exact tie-break.
    pub ambiguous: bool,
    /// Codes above this always split: `floor + 1` when ambiguous, else `floor`.
    pub tie: u16,
    /// The threshold as the largest `f32` not above `E`.
    pub threshold: f32,
}

impl SplitRule {
    /// The rule for a threshold of `e_m` metres (non-negative, not NaN).
    pub fn new(e_m: f64) -> Self {
        let threshold = threshold_f32(e_m.max(0.0));
        // At most INFINITE − 2, so that INFINITE is always above `tie`.
        let floor = (threshold.to_bits() >> 15).min(u32::from(INFINITE) - 2) as u16;
        let ambiguous = decode(floor) < threshold;
        SplitRule {
            floor,
            ambiguous,
            tie: floor + u16::from(ambiguous),
            threshold,
        }
    }

    /// The rule for the threshold `decode(code)`: never ambiguous.
    pub fn at_code(code: u16) -> Self {
        let code = code.min(INFINITE - 2);
        SplitRule {
            floor: code,
            ambiguous: false,
            tie: code,
            threshold: decode(code),
        }
    }

    /// `Some(split)` when the code alone decides, `None` for the tie-break.
    #[inline(always)]
    pub fn decide(&self, code: u16) -> Option<bool> {
        if code > self.tie {
            Some(true)
        } else if code <= self.floor {
            Some(false)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn codes_bound_from_above_and_keep_order() {
        let mut prev = 0u16;
        let mut x = 0f32;
        while x < 1e6 {
            let c = encode_up(x);
            assert!(decode(c) >= x, "{x}");
            assert!(c >= prev);
            if c > 0 {
                assert!(decode(c - 1) < x, "{x} is not the smallest code");
            }
            prev = c;
            x = x * 1.013 + 0.0007;
        }
        assert_eq!(encode_up(f32::INFINITY), INFINITE);
        assert_eq!(decode(INFINITE), f32::INFINITY);
        assert_eq!(encode_up(0.0), 0);
        assert_eq!(encode_up(f32::NAN), INFINITE);
    }

    #[test]
    fn round_thresholds_are_never_ambiguous() {
        for e in [
            0.0, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0, 20.0, 50.0, 100.0, 1000.0,
        ] {
            assert!(!SplitRule::new(e).ambiguous, "{e}");
        }
        assert!(SplitRule::new(0.3).ambiguous);
    }

    #[test]
    fn rule_agrees_with_the_exact_comparison_whenever_it_decides() {
        for e in [0.0, 0.3, 0.5, 1.7, 3.3217, 5.0, 47.975, 1e5] {
            let rule = SplitRule::new(e);
            let mut x = 0f32;
            while x < 2e5 {
                let exact = x as f64 > e;
                if let Some(d) = rule.decide(encode_up(x)) {
                    assert_eq!(d, exact, "x={x} e={e}");
                }
                x = x * 1.002 + 0.0001;
            }
            assert_eq!(rule.decide(INFINITE), Some(true));
        }
    }
}
