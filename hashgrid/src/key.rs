//! Keys of grid vertices: integer coordinates, level, normal class and free bits.

use bytemuck::{Pod, Zeroable};
use glam::{IVec3, Vec3};

use crate::constants::{CLASS_NONE, CLASS_SHIFT, EXTRA_SHIFT, LEVEL_SHIFT};

/// The key of one grid vertex: what the bucket hash and the checksum are computed from.
///
/// MCPG (sec. 4, "Hash Grid") hashes the integer grid coordinate, and for the adaptive grid
/// also the level and the cube-map index of the surface normal, "to prevent information from
/// leaking through surfaces and around sharp corners". Here all of it lives in four 32-bit
/// words, `[x, y, z, meta]`, which is also the layout in memory (`#[repr(C)]`, 16 bytes):
///
/// | word | bits | field | range |
/// |---|---|---|---|
/// | 0..3 | 32 each | `cell` (x, y, z) | all of `i32` |
/// | 3 (`meta`) | 0..8 | `level` | 0..=255 ([`MAX_LEVEL`](crate::constants::MAX_LEVEL)) |
/// | 3 (`meta`) | 8..16 | `class` | 0..=5 normal classes ([`normal_class`]), 6 = none ([`CLASS_NONE`]), 7..=255 free |
/// | 3 (`meta`) | 16..32 | `extra` | free: e.g. a view-direction class for volumes, a jitter index |
///
/// Level and class are in the low bits so that even the xor-of-primes hash carries them into
/// the low bits of the bucket hash (see [`LEVEL_BITS`](crate::constants::LEVEL_BITS)).
///
/// The level and class are part of both the bucket hash and the checksum, so cells of
/// different levels or normal classes never alias (a public Rust cache aliases levels because
/// its key lacks them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct CellKey {
    /// Integer vertex coordinate: world position / cell width, rounded to a lattice point.
    pub cell: IVec3,
    /// Level of the adaptive grid, 0 for the finest (meta bits 0..8).
    pub level: u8,
    /// Normal class 0..=5 from [`normal_class`], or [`CLASS_NONE`] (meta bits 8..16).
    pub class: u8,
    /// Free bits (meta bits 16..32).
    pub extra: u16,
}

const _: () = assert!(core::mem::size_of::<CellKey>() == 16);

impl CellKey {
    /// A key with the given coordinate, level and class, and no extra bits.
    #[inline]
    #[must_use]
    pub const fn new(cell: IVec3, level: u8, class: u8) -> Self {
        Self {
            cell,
            extra: 0,
            class,
            level,
        }
    }

    /// A key of a grid without levels and normals (MCPG's static grid): level 0,
    /// class [`CLASS_NONE`].
    #[inline]
    #[must_use]
    pub const fn unclassed(cell: IVec3) -> Self {
        Self::new(cell, 0, CLASS_NONE)
    }

    /// The same key with `extra` as its free bits.
    #[inline]
    #[must_use]
    pub const fn with_extra(self, extra: u16) -> Self {
        Self { extra, ..self }
    }

    /// The meta word: `extra << 16 | class << 8 | level`.
    #[inline]
    #[must_use]
    pub const fn meta(&self) -> u32 {
        ((self.extra as u32) << EXTRA_SHIFT)
            | ((self.class as u32) << CLASS_SHIFT)
            | ((self.level as u32) << LEVEL_SHIFT)
    }

    /// The four words the hashes read: `[x, y, z, meta]` with the coordinates' two's-complement
    /// bits.
    #[inline]
    #[must_use]
    pub const fn words(&self) -> [u32; 4] {
        [
            self.cell.x as u32,
            self.cell.y as u32,
            self.cell.z as u32,
            self.meta(),
        ]
    }

    /// The key whose [`words`](Self::words) are `words` (the inverse of `words`).
    #[inline]
    #[must_use]
    pub const fn from_words(words: [u32; 4]) -> Self {
        let meta = words[3];
        Self {
            cell: IVec3::new(words[0] as i32, words[1] as i32, words[2] as i32),
            level: (meta >> LEVEL_SHIFT) as u8,
            class: (meta >> CLASS_SHIFT) as u8,
            extra: (meta >> EXTRA_SHIFT) as u16,
        }
    }
}

/// The cube-map face of a direction: its dominant axis and sign, `2·axis + (component < 0)`,
/// so +x → 0, −x → 1, +y → 2, −y → 3, +z → 4, −z → 5 (MCPG sec. 4: "we computed the cube map
/// index based on the surface normal and hash the result along with the grid coordinates").
///
/// `n` need not be normalised. Ties go to the lower axis (x before y before z); a component
/// of −0.0 counts as positive. Degenerate input never panics: the zero vector gives 0 (+x), and
/// NaN components never win a comparison, so an all-NaN vector gives 4 (+z). The same rule is
/// used for view directions of volume samples (MCPG sec. 4, "Extension to Single Scattering").
#[inline]
#[must_use]
pub fn normal_class(n: Vec3) -> u8 {
    let a = n.abs();
    let (axis, component) = if a.x >= a.y && a.x >= a.z {
        (0, n.x)
    } else if a.y >= a.z {
        (1, n.y)
    } else {
        (2, n.z)
    };
    2 * axis + u8::from(component < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_classes_of_the_axes() {
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (i, &a) in axes.iter().enumerate() {
            assert_eq!(normal_class(a), i as u8);
            assert_eq!(normal_class(a * 3.0 + Vec3::splat(0.1)), i as u8);
        }
        assert_eq!(normal_class(Vec3::ZERO), 0);
        assert_eq!(normal_class(Vec3::NAN), 4);
        assert_eq!(normal_class(Vec3::new(1.0, 1.0, 1.0)), 0);
        assert_eq!(normal_class(Vec3::new(0.0, -1.0, 1.0)), 3);
        assert_eq!(normal_class(Vec3::new(-0.0, 0.0, 0.0)), 0);
        assert_eq!(normal_class(Vec3::new(f32::NAN, 0.2, -0.5)), 5);
    }

    #[test]
    fn words_round_trip_and_match_memory() {
        let key = CellKey::new(IVec3::new(-3, 7, i32::MIN), 200, 5).with_extra(0xBEEF);
        let words = key.words();
        assert_eq!(words[3], (0xBEEF << 16) | (5 << 8) | 200);
        assert_eq!(CellKey::from_words(words), key);
        let bytes: [u32; 4] = bytemuck::cast(key);
        if cfg!(target_endian = "little") {
            assert_eq!(bytes, words);
        }
        assert_eq!(CellKey::unclassed(IVec3::ONE).class, CLASS_NONE);
    }

    #[test]
    fn value_stability() {
        let key = CellKey::new(
            IVec3::new(1, -2, 3),
            7,
            normal_class(Vec3::new(0.1, -0.9, 0.3)),
        );
        assert_eq!(key.words(), [1, 0xFFFF_FFFE, 3, 0x0000_0307]);
    }
}
