//! ADGI's virtual proxies (sec. 4.9): the probe grid coarsened into blocks of 3 × 3 × 3 probes,
//! each with 8 octant texels holding the **max** of its probes' values, on which the dynamic
//! Metropolis chains run.
//!
//! Sec. 4.9: "we solve the first issue [chains lagging a moving target] by increasing the chain
//! step size and by coarsening the target function (f_d). Practically, this amounts to grouping
//! the heuristics-probes into virtual proxies. \[...\] a virtual proxy represents a group \[of\] the
//! 3 × 3 × 3 probes. This virtual probe has 8 directions and each direction represents an
//! axis-aligned octant. The value of a texel of the virtual probe is the max of all 27 probes it
//! represents along the corresponding direction." A sample of the dynamic chain names a proxy
//! and an octant; the renderer then traces that octant for every (unculled) probe of the block.
//!
//! [`ProxyGrid`] is that grouping for any block size; a block size of 1 is the probe grid
//! itself, so the static chains and the guiding function use the same type.

use glam::{UVec3, Vec3};

use crate::heuristics::OCTANTS;
use crate::{GridError, LayoutError, ProbeGrid};

/// ADGI's proxy block: 3 × 3 × 3 probes (sec. 4.9).
pub const ADGI_PROXY_BLOCK: u32 = 3;

/// A probe grid grouped into cubic blocks of `block³` probes (ADGI's virtual proxies, sec. 4.9).
///
/// Proxy `(i, j, k)` holds probes `block·(i, j, k) + [0, block)³` that exist; proxies on the
/// grid's upper faces may hold fewer. Proxies are indexed x fastest, like probes. Positions
/// map to the proxy of their nearest probe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyGrid {
    grid: ProbeGrid,
    block: u32,
    counts: UVec3,
}

impl ProxyGrid {
    /// The probes themselves, as blocks of one probe (what the static chains sample, sec. 4.8).
    #[must_use]
    pub fn probes(grid: ProbeGrid) -> Self {
        Self {
            grid,
            block: 1,
            counts: grid.counts(),
        }
    }

    /// ADGI's virtual proxies of 3 × 3 × 3 probes (sec. 4.9).
    #[must_use]
    pub fn adgi(grid: ProbeGrid) -> Self {
        Self::probes(grid).with_block(ADGI_PROXY_BLOCK)
    }

    /// Blocks of `block³` probes.
    ///
    /// # Errors
    /// [`GridError::ProxyBlockZero`] for `block = 0`.
    pub fn new(grid: ProbeGrid, block: u32) -> Result<Self, GridError> {
        if block == 0 {
            return Err(GridError::ProxyBlockZero);
        }
        Ok(Self::probes(grid).with_block(block))
    }

    fn with_block(self, block: u32) -> Self {
        Self {
            grid: self.grid,
            block,
            // ⌈c / block⌉ as (c − 1)/block + 1 (c ≥ 1): `c + block − 1` overflows for large blocks.
            counts: (self.grid.counts() - UVec3::ONE) / block + UVec3::ONE,
        }
    }

    /// The underlying probe grid.
    #[inline]
    #[must_use]
    pub fn grid(&self) -> ProbeGrid {
        self.grid
    }

    /// Probes per block edge.
    #[inline]
    #[must_use]
    pub fn block(&self) -> u32 {
        self.block
    }

    /// Proxies along each axis, `⌈probe counts / block⌉`.
    #[inline]
    #[must_use]
    pub fn counts(&self) -> UVec3 {
        self.counts
    }

    /// Number of proxies.
    #[inline]
    #[must_use]
    pub fn proxy_count(&self) -> usize {
        (self.counts.x * self.counts.y * self.counts.z) as usize
    }

    /// Length of a per-proxy octant table: `proxy_count() · 8`.
    #[inline]
    #[must_use]
    pub fn table_len(&self) -> usize {
        self.proxy_count() * OCTANTS
    }

    /// Linear index of the proxy at proxy coordinates `coords` (x fastest).
    #[inline]
    #[must_use]
    pub fn proxy_index(&self, coords: UVec3) -> usize {
        crate::grid::linear_index(self.counts, coords)
    }

    /// Proxy coordinates of linear index `index`.
    #[inline]
    #[must_use]
    pub fn proxy_coords(&self, index: usize) -> UVec3 {
        crate::grid::linear_coords(self.counts, index)
    }

    /// Index of the proxy holding the probe at probe coordinates `probe`.
    #[inline]
    #[must_use]
    pub fn proxy_of_probe(&self, probe: UVec3) -> usize {
        self.proxy_index(probe / self.block)
    }

    /// Coordinates of the probe nearest to `point`, if `point` lies in the grid's sampling
    /// domain: the box of the probes' Voronoi cells, `origin − spacing/2 ≤ point <
    /// origin + (counts − 1/2) · spacing` (every probe owns an equal box of volume
    /// `spacing.x · spacing.y · spacing.z`). `None` outside it and for NaN.
    #[inline]
    #[must_use]
    pub fn nearest_probe(&self, point: Vec3) -> Option<UVec3> {
        let t = (point - self.grid.origin()) / self.grid.spacing() + Vec3::splat(0.5);
        let counts = self.grid.counts().as_vec3();
        // Written so NaN fails.
        if !(t.cmpge(Vec3::ZERO).all() && t.cmplt(counts).all()) {
            return None;
        }
        Some(t.as_uvec3().min(self.grid.counts() - UVec3::ONE))
    }

    /// Index of the proxy whose probes own `point` (see [`Self::nearest_probe`]).
    #[inline]
    #[must_use]
    pub fn proxy_at(&self, point: Vec3) -> Option<usize> {
        self.nearest_probe(point).map(|c| self.proxy_of_probe(c))
    }

    /// The probes of proxy `index`, as probe coordinates (x fastest).
    pub fn probes_of(&self, index: usize) -> impl Iterator<Item = UVec3> + use<> {
        let lo = self.proxy_coords(index) * self.block;
        let hi = lo
            .saturating_add(UVec3::splat(self.block))
            .min(self.grid.counts());
        (lo.z..hi.z).flat_map(move |z| {
            (lo.y..hi.y).flat_map(move |y| (lo.x..hi.x).map(move |x| UVec3::new(x, y, z)))
        })
    }

    /// Number of probes in proxy `index` (`block³` inside the grid, fewer on its upper faces).
    #[inline]
    #[must_use]
    pub fn probes_in(&self, index: usize) -> u32 {
        let lo = self.proxy_coords(index) * self.block;
        let hi = lo
            .saturating_add(UVec3::splat(self.block))
            .min(self.grid.counts());
        let n = hi - lo;
        n.x * n.y * n.z
    }

    /// The proxies' octant texels: for every proxy and octant, the max over its probes of the
    /// per-probe octant table `per_probe` (ADGI sec. 4.9: "the max of all 27 probes it represents
    /// along the corresponding direction"). NaN entries are skipped; a proxy whose entries are
    /// all NaN gets 0. Tables are indexed `probe_index · 8 + octant`.
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] unless `per_probe.len() == probe_count · 8` and
    /// `out.len() == self.table_len()`.
    pub fn max_pool(&self, per_probe: &[f32], out: &mut [f32]) -> Result<(), LayoutError> {
        LayoutError::check_tables(self.grid.probe_count() * OCTANTS, &[per_probe.len()])?;
        LayoutError::check_tables(self.table_len(), &[out.len()])?;
        out.fill(0.0);
        for probe in 0..self.grid.probe_count() {
            let proxy = self.proxy_of_probe(self.grid.probe_coords(probe));
            let src = &per_probe[probe * OCTANTS..][..OCTANTS];
            let dst = &mut out[proxy * OCTANTS..][..OCTANTS];
            for (d, &s) in dst.iter_mut().zip(src) {
                // `max` skips NaN; 0 is the floor.
                *d = d.max(s);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> ProbeGrid {
        ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::new(7, 3, 4)).unwrap()
    }

    #[test]
    fn counts_and_membership() {
        let p = ProxyGrid::adgi(grid());
        assert_eq!(p.counts(), UVec3::new(3, 1, 2));
        assert_eq!(p.proxy_count(), 6);
        assert_eq!(p.block(), 3);
        assert_eq!(ProxyGrid::new(grid(), 0), Err(GridError::ProxyBlockZero));
        let mut seen = vec![0u32; grid().probe_count()];
        for proxy in 0..p.proxy_count() {
            assert_eq!(p.proxy_index(p.proxy_coords(proxy)), proxy);
            let mut n = 0;
            for c in p.probes_of(proxy) {
                assert_eq!(p.proxy_of_probe(c), proxy);
                seen[grid().probe_index(c)] += 1;
                n += 1;
            }
            assert_eq!(n, p.probes_in(proxy));
        }
        assert!(
            seen.iter().all(|&s| s == 1),
            "every probe in exactly one proxy"
        );
        // Proxy (2, 0, 1) holds x ∈ {6}, y ∈ {0, 1, 2}, z ∈ {3}: 3 probes.
        assert_eq!(p.probes_in(p.proxy_index(UVec3::new(2, 0, 1))), 3);
        assert_eq!(ProxyGrid::probes(grid()).proxy_count(), 84);
    }

    #[test]
    fn huge_blocks_hold_the_whole_grid() {
        // Issue 14 row 14: `counts + block − 1` overflowed (debug panic); release gave 0
        // proxies while `proxy_at` still returned Some(0).
        for block in [7, 8, 1 << 31, u32::MAX - 1, u32::MAX] {
            let p = ProxyGrid::new(grid(), block).unwrap();
            assert_eq!(p.counts(), UVec3::ONE, "{block}");
            assert_eq!(p.proxy_count(), 1);
            assert_eq!(p.table_len(), 8);
            assert_eq!(p.proxy_at(Vec3::new(1.0, 0.5, 1.0)), Some(0));
            assert_eq!(p.probes_in(0), 84);
            assert_eq!(p.probes_of(0).count(), 84);
        }
        // A long axis with a block of 2³¹: ⌈3·10⁹ / 2³¹⌉ = 2 proxies, the second holding the
        // rest of the axis.
        let long = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(3_000_000_000, 1, 1)).unwrap();
        let p = ProxyGrid::new(long, 1 << 31).unwrap();
        assert_eq!(p.counts(), UVec3::new(2, 1, 1));
        assert_eq!(p.probes_in(1), 3_000_000_000 - (1 << 31));
    }

    #[test]
    fn nearest_probe_owns_equal_boxes() {
        let p = ProxyGrid::probes(grid());
        // Spacing 0.5: probe i owns [0.5 i − 0.25, 0.5 i + 0.25).
        assert_eq!(
            p.nearest_probe(Vec3::new(-0.25, 0.0, 0.0)),
            Some(UVec3::ZERO)
        );
        assert_eq!(p.nearest_probe(Vec3::new(-0.26, 0.0, 0.0)), None);
        assert_eq!(
            p.nearest_probe(Vec3::new(0.26, 0.74, 1.74)),
            Some(UVec3::new(1, 1, 3))
        );
        assert_eq!(
            p.nearest_probe(Vec3::new(3.24, 1.2, 1.7)),
            Some(UVec3::new(6, 2, 3))
        );
        assert_eq!(p.nearest_probe(Vec3::new(3.25, 0.0, 0.0)), None);
        assert_eq!(p.nearest_probe(Vec3::NAN), None);
        let a = ProxyGrid::adgi(grid());
        // Probe (4, 1, 3) is in proxy (1, 0, 1) = 1 + 3·(0 + 1) = 4.
        assert_eq!(a.proxy_at(Vec3::new(2.0, 0.5, 1.5)), Some(4));
    }

    #[test]
    fn max_pool_by_hand() {
        let g = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(4, 1, 1)).unwrap();
        let p = ProxyGrid::adgi(g);
        assert_eq!(p.proxy_count(), 2);
        // Probe i, octant o holds i + o/10; probe 1 octant 2 is NaN.
        let mut table: Vec<f32> = (0..32)
            .map(|k| (k / 8) as f32 + (k % 8) as f32 / 10.0)
            .collect();
        table[8 + 2] = f32::NAN;
        let mut out = vec![0.0; 16];
        p.max_pool(&table, &mut out).unwrap();
        // Proxy 0 = probes 0, 1, 2: max is probe 2 (2 + o/10); proxy 1 = probe 3 alone.
        for o in 0..8 {
            mcg_test_support::assert_close!(out[o], (2.0 + o as f32 / 10.0), 1e-6);
            mcg_test_support::assert_close!(out[8 + o], (3.0 + o as f32 / 10.0), 1e-6);
        }
        assert_eq!(
            p.max_pool(&table[1..], &mut out),
            Err(LayoutError::TableLengthMismatch {
                expected: table.len(),
                found: table.len() - 1
            })
        );
    }

    #[test]
    fn value_stability() {
        let g = ProbeGrid::new(
            Vec3::new(-1.0, 0.5, 2.0),
            Vec3::new(0.5, 1.0, 0.25),
            UVec3::new(5, 4, 7),
        )
        .unwrap();
        let p = ProxyGrid::adgi(g);
        let got: Vec<Option<usize>> = [
            Vec3::new(0.3, 2.9, 3.1),
            Vec3::new(-1.2, 0.1, 1.9),
            Vec3::new(1.2, 4.0, 3.6),
        ]
        .iter()
        .map(|&x| p.proxy_at(x))
        .collect();
        // (0.3, 2.9, 3.1) → t = (3.1, 2.9, 4.9) → probe (3, 2, 4) → proxy (1, 0, 1) = 5;
        // the second → probe 0; the third has t.y = 4.0 = counts.y → outside.
        assert_eq!(got, vec![Some(5), Some(0), None], "{got:?}");
    }
}
