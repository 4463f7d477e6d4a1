//! A bit field inside a 32-bit word.

/// `bits` bits starting at bit `shift` (bit 0 is the least significant). A zero-width field
/// (`bits` = 0, e.g. a layout without flag bits, at `shift` = 32) reads as 0 and writes
/// nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct BitField {
    pub shift: u32,
    pub bits: u32,
}

impl BitField {
    pub const fn new(shift: u32, bits: u32) -> Self {
        Self { shift, bits }
    }

    /// All ones in the field's width (not shifted).
    #[inline(always)]
    pub const fn max(self) -> u32 {
        if self.bits >= 32 {
            u32::MAX
        } else {
            (1u32 << self.bits) - 1
        }
    }

    /// The shift, or 0 for a zero-width field (whose shift may be 32, which `>>` and `<<` on
    /// `u32` do not allow; the mask is 0 there anyway).
    #[inline(always)]
    const fn safe_shift(self) -> u32 {
        if self.bits == 0 { 0 } else { self.shift }
    }

    /// The field's value in `word`.
    #[inline(always)]
    pub const fn get(self, word: u32) -> u32 {
        (word >> self.safe_shift()) & self.max()
    }

    /// `value` (masked to the width) moved into place.
    #[inline(always)]
    pub const fn put(self, value: u32) -> u32 {
        (value & self.max()) << self.safe_shift()
    }

    /// `word` with this field replaced by `value`.
    #[inline(always)]
    pub const fn set(self, word: u32, value: u32) -> u32 {
        (word & !(self.max() << self.safe_shift())) | self.put(value)
    }
}
