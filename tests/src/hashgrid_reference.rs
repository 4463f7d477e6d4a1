//! Structured streams of grid keys, as a renderer produces them, for the hash-grid suites.
//!
//! Each stream is a list of *distinct* [`CellKey`]s: the grid vertices that a scene surface
//! touches. Structured streams are what breaks weak spatial hashes (Teschner et al. 2003 test
//! the same way): keys on a plane share one coordinate, keys on a line share two.

use std::collections::HashSet;

use glam::{IVec3, Vec3};
use mcg_hashgrid::{AdaptiveGrid, CellKey, normal_class};

/// The vertices of an axis-aligned square plane: x, y ∈ [x0, x0 + side), z = `z`, level 0,
/// class 4 (+z). `side²` keys.
#[must_use]
pub fn plane_keys(side: i32, x0: i32, z: i32) -> Vec<CellKey> {
    let mut keys = Vec::with_capacity((side * side) as usize);
    for y in 0..side {
        for x in 0..side {
            keys.push(CellKey::new(IVec3::new(x0 + x, x0 + y, z), 0, 4));
        }
    }
    keys
}

/// The vertices of a line along `direction` (integer steps), `n` keys from `start`, level 0,
/// class 0.
#[must_use]
pub fn line_keys(n: i32, start: IVec3, direction: IVec3) -> Vec<CellKey> {
    (0..n)
        .map(|i| CellKey::new(start + direction * i, 0, 0))
        .collect()
}

/// A voxelised sphere surface: every lattice vertex within half a cell of the sphere of
/// radius `radius` (in cells) around `center`, with the class of its outward normal and
/// level `level`. About 4πr² keys.
#[must_use]
pub fn sphere_shell_keys(radius: f32, center: IVec3, level: u8) -> Vec<CellKey> {
    let r = radius.ceil() as i32 + 1;
    let mut keys = Vec::new();
    for z in -r..=r {
        for y in -r..=r {
            for x in -r..=r {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                if (p.length() - radius).abs() <= 0.5 {
                    keys.push(CellKey::new(
                        center + IVec3::new(x, y, z),
                        level,
                        normal_class(p),
                    ));
                }
            }
        }
    }
    keys
}

/// The distinct adaptive-grid keys that a camera at `camera` looking at the floor plane
/// y = 0 produces for a `resolution²` grid of floor points in [−extent, extent]², with MCPG's
/// adaptive grid (levels from distance, no jitter, lower-corner vertex): a multi-level stream.
#[must_use]
pub fn floor_view_keys(
    grid: &AdaptiveGrid,
    camera: Vec3,
    extent: f32,
    resolution: u32,
) -> Vec<CellKey> {
    let mut seen = HashSet::new();
    let mut keys = Vec::new();
    for j in 0..resolution {
        for i in 0..resolution {
            let p = Vec3::new(
                -extent + 2.0 * extent * (i as f32 + 0.5) / resolution as f32,
                0.0,
                -extent + 2.0 * extent * (j as f32 + 0.5) / resolution as f32,
            );
            let key = grid.vertex_key(p, Vec3::Y, camera, 0.0, 0.0);
            if seen.insert(key) {
                keys.push(key);
            }
        }
    }
    keys
}

/// Counts of `index(hash(key))` over `keys` in `bins` bins.
#[must_use]
pub fn occupancy(keys: &[CellKey], bins: u32, hash: impl Fn(&CellKey) -> u32) -> Vec<u64> {
    let ix = mcg_hashgrid::SlotIndexer::new(bins).expect("bins > 0");
    let mut counts = vec![0_u64; bins as usize];
    for k in keys {
        counts[ix.index(hash(k)) as usize] += 1;
    }
    counts
}
