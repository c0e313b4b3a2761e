//! The entropy coder of the progressive stream ([`crate::stream`]): an
//! adaptive binary range coder and the binarisation of signed residuals.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3 ("Transmisión progresiva") sends, per
//! tolerance, the points it adds; this file only decides how few bits those
//! decisions and heights take.
//!
//! 1. **Range coder.** A carry-propagating binary range coder over a 32-bit
//!    range and a 64-bit `low` (the classic arithmetic-coding construction of
//!    Rissanen/Langdon and Martin's range coding). Each bit is coded with a
//!    12-bit probability that the bit is 0; after coding, the probability moves
//!    `1/32` of the way towards what was seen (exponential forgetting), so
//!    models adapt to each level of the hierarchy without any table.
//! 2. **Byte layout of one coded block**: the encoder emits one leading byte
//!    (always 0, the initial carry cache) then the big-endian digits of `low`;
//!    [`RangeEncoder::finish`] flushes 5 bytes so that the decoder, which
//!    primes itself with 5 bytes, never reads past the block. A decoder that
//!    needs bytes beyond the block reads zeros and reports it
//!    ([`RangeDecoder::overrun`]): the block was truncated or corrupted.
//! 3. **Residuals** ([`ResidualModel`]): a signed integer `r` is sent as
//!    `r == 0` (adaptive), then the sign (adaptive), then `n`, the bit length of
//!    `|r|` (1..=[`MAX_BITS`]), in unary with one adaptive probability per
//!    position, then the `n − 1` bits of `|r|` below its leading one: the
//!    first under a probability chosen by `n`, the others at a fixed 1/2.
//!
//! No allocation per bit, no floating point: encoder and decoder are exact
//! mirrors, so a model state never diverges between them.

/// Bits of precision of a probability.
const PROB_BITS: u32 = 12;
/// A probability of 1/2.
const PROB_HALF: u16 = 1 << (PROB_BITS - 1);
/// Adaptation speed: probabilities move `1/2^ADAPT` towards each coded bit.
const ADAPT: u32 = 5;
/// The range is renormalised when it falls below this.
const TOP: u32 = 1 << 24;
/// Largest bit length of a residual magnitude.
pub const MAX_BITS: usize = 48;

/// One adaptive binary probability (of a 0 bit), starting at 1/2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bit(u16);

impl Default for Bit {
    fn default() -> Self {
        Bit(PROB_HALF)
    }
}

impl Bit {
    #[inline]
    fn update(&mut self, bit: bool) {
        if bit {
            self.0 -= self.0 >> ADAPT;
        } else {
            self.0 += ((1 << PROB_BITS) - self.0) >> ADAPT;
        }
    }
}

/// The encoding half of the range coder.
#[derive(Debug, Clone)]
pub struct RangeEncoder {
    low: u64,
    range: u32,
    cache: u8,
    cache_size: u64,
    out: Vec<u8>,
}

impl Default for RangeEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RangeEncoder {
    /// A fresh encoder with an empty output.
    pub fn new() -> Self {
        RangeEncoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            out: Vec::new(),
        }
    }

    /// Codes `bit` with the adaptive probability `p`, then adapts `p`.
    #[inline]
    pub fn bit(&mut self, p: &mut Bit, bit: bool) {
        let bound = (self.range >> PROB_BITS) * p.0 as u32;
        if bit {
            self.low += bound as u64;
            self.range -= bound;
        } else {
            self.range = bound;
        }
        p.update(bit);
        self.normalize();
    }

    /// Codes `bit` at a fixed probability of 1/2.
    #[inline]
    pub fn bypass(&mut self, bit: bool) {
        let mut p = Bit::default();
        self.bit(&mut p, bit);
    }

    #[inline]
    fn normalize(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    fn shift_low(&mut self) {
        if self.low < 0xFF00_0000 || self.low > 0xFFFF_FFFF {
            let carry = (self.low >> 32) as u8;
            let mut digit = self.cache;
            loop {
                self.out.push(digit.wrapping_add(carry));
                digit = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Flushes the coder and returns the coded block.
    pub fn finish(mut self) -> Vec<u8> {
        for _ in 0..5 {
            self.shift_low();
        }
        self.out
    }
}

/// The decoding half of the range coder, over one coded block.
#[derive(Debug, Clone)]
pub struct RangeDecoder<'a> {
    data: &'a [u8],
    pos: usize,
    code: u32,
    range: u32,
    overrun: usize,
}

impl<'a> RangeDecoder<'a> {
    /// Starts decoding `data` (one block from [`RangeEncoder::finish`]).
    pub fn new(data: &'a [u8]) -> Self {
        let mut d = RangeDecoder {
            data,
            pos: 0,
            code: 0,
            range: u32::MAX,
            overrun: 0,
        };
        for _ in 0..5 {
            d.code = (d.code << 8) | d.next_byte() as u32;
        }
        d
    }

    #[inline]
    fn next_byte(&mut self) -> u8 {
        match self.data.get(self.pos) {
            Some(&b) => {
                self.pos += 1;
                b
            }
            None => {
                self.overrun += 1;
                0
            }
        }
    }

    /// Bytes the decoder needed beyond the block (0 for an intact block).
    pub fn overrun(&self) -> usize {
        self.overrun
    }

    /// Bytes of the block consumed so far.
    pub fn consumed(&self) -> usize {
        self.pos
    }

    /// Decodes one bit with the adaptive probability `p`, then adapts `p`.
    #[inline]
    pub fn bit(&mut self, p: &mut Bit) -> bool {
        let bound = (self.range >> PROB_BITS) * p.0 as u32;
        let bit = if self.code < bound {
            self.range = bound;
            false
        } else {
            self.code -= bound;
            self.range -= bound;
            true
        };
        p.update(bit);
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | self.next_byte() as u32;
        }
        bit
    }

    /// Decodes a bit coded with [`RangeEncoder::bypass`].
    #[inline]
    pub fn bypass(&mut self) -> bool {
        let mut p = Bit::default();
        self.bit(&mut p)
    }
}

/// Adaptive models for one context of signed residuals (see the module docs).
#[derive(Debug, Clone)]
pub struct ResidualModel {
    zero: Bit,
    sign: Bit,
    length: [Bit; MAX_BITS],
    first: [Bit; MAX_BITS],
}

impl Default for ResidualModel {
    fn default() -> Self {
        ResidualModel {
            zero: Bit::default(),
            sign: Bit::default(),
            length: [Bit::default(); MAX_BITS],
            first: [Bit::default(); MAX_BITS],
        }
    }
}

impl ResidualModel {
    /// Encodes `r`; `|r|` must be below `2^MAX_BITS` (the caller checks).
    pub fn encode(&mut self, enc: &mut RangeEncoder, r: i64) {
        enc.bit(&mut self.zero, r != 0);
        if r == 0 {
            return;
        }
        enc.bit(&mut self.sign, r < 0);
        let a = r.unsigned_abs();
        let n = (64 - a.leading_zeros()) as usize; // 1..=MAX_BITS
        for k in 1..n.min(MAX_BITS) {
            enc.bit(&mut self.length[k - 1], true);
        }
        if n < MAX_BITS {
            enc.bit(&mut self.length[n - 1], false);
        }
        if n >= 2 {
            enc.bit(&mut self.first[n - 1], (a >> (n - 2)) & 1 == 1);
            for k in (0..n.saturating_sub(2)).rev() {
                enc.bypass((a >> k) & 1 == 1);
            }
        }
    }

    /// Decodes a residual coded by [`ResidualModel::encode`].
    pub fn decode(&mut self, dec: &mut RangeDecoder<'_>) -> i64 {
        if !dec.bit(&mut self.zero) {
            return 0;
        }
        let negative = dec.bit(&mut self.sign);
        let mut n = 1;
        while n < MAX_BITS && dec.bit(&mut self.length[n - 1]) {
            n += 1;
        }
        let mut a: u64 = 1;
        if n >= 2 {
            a = (a << 1) | dec.bit(&mut self.first[n - 1]) as u64;
            for _ in 0..n - 2 {
                a = (a << 1) | dec.bypass() as u64;
            }
        }
        let a = a as i64;
        if negative {
            -a
        } else {
            a
        }
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn bits_and_residuals_round_trip() {
        let values: Vec<i64> = (0..5000)
            .map(|i: i64| {
                let x = (i * 7919 + 13) % 1001 - 500;
                if i % 97 == 0 {
                    x * 1_000_000_007
                } else {
                    x / ((i % 7) + 1)
                }
            })
            .collect();
        let mut enc = RangeEncoder::new();
        let mut m = ResidualModel::default();
        let mut flag = Bit::default();
        for (i, &v) in values.iter().enumerate() {
            enc.bit(&mut flag, i % 3 == 0);
            m.encode(&mut enc, v);
        }
        let bytes = enc.finish();
        let mut dec = RangeDecoder::new(&bytes);
        let mut m = ResidualModel::default();
        let mut flag = Bit::default();
        for (i, &v) in values.iter().enumerate() {
            assert_eq!(dec.bit(&mut flag), i % 3 == 0);
            assert_eq!(m.decode(&mut dec), v);
        }
        assert_eq!(dec.overrun(), 0);
        assert_eq!(dec.consumed(), bytes.len());
    }

    #[test]
    fn skewed_bits_cost_little() {
        let mut enc = RangeEncoder::new();
        let mut p = Bit::default();
        for i in 0..80_000 {
            enc.bit(&mut p, i % 100 == 0);
        }
        // Entropy of p = 0.01 is 0.081 bit: about 810 bytes.
        assert!(enc.finish().len() < 1100);
    }
}
