//! MCPG's ensemble of hash grids on the CPU: `grid.load` and `grid.store` of Alg. 1 and 3.

use mcg_hashgrid::{AdaptiveGrid, BucketHash, CellKey, HashTable, StaticGrid, TableError};
use mcg_vmf::glam::Vec3;

use super::{GridKind, GridState};

/// Where a loaded state came from, so that the discard heuristic can zero it there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridSlot {
    /// The grid.
    pub grid: GridKind,
    /// The slot in that grid's table.
    pub slot: u32,
}

/// The uniforms of one `grid.load` or `grid.store`: which grid, the level jitter and the corner.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridUniforms {
    /// Chooses the adaptive grid when below p_adaptive.
    pub grid: f32,
    /// ξ of the geometric jitter to coarser levels.
    pub level: f32,
    /// The stochastic trilinear corner.
    pub corner: f32,
}

/// MCPG's hash-grid ensemble (sec. 4): an adaptive multi-level grid whose key holds the normal
/// class, and a coarse static grid without it, each a [`HashTable`] of [`GridState`]s (the
/// checksum array holds the key, Table 1's "hash").
///
/// A vertex is chosen anew for every access: adaptive with probability p_adaptive, level by
/// camera distance with geometric jitter towards coarser levels, corner by stochastic
/// trilinear interpolation ([`AdaptiveGrid::vertex_key`], [`StaticGrid::vertex_key`]). A key
/// the table does not hold reads as the empty state (w̄ = 0, as Alg. 1 line 7 treats a
/// collision); a store into a full neighbourhood is dropped.
#[derive(Clone, Debug)]
pub struct GridEnsemble {
    /// The adaptive grid's geometry.
    pub adaptive: AdaptiveGrid,
    /// The static grid's geometry.
    pub static_grid: StaticGrid,
    /// The adaptive grid's states.
    pub adaptive_table: HashTable<GridState>,
    /// The static grid's states.
    pub static_table: HashTable<GridState>,
    /// p_adaptive (MCPG: 0.7).
    pub adaptive_probability: f32,
}

impl GridEnsemble {
    /// MCPG's grids ([`AdaptiveGrid::mcpg`], [`StaticGrid::mcpg`]) with tables of the given
    /// capacities, probing at most 8 slots, the mixing hash.
    ///
    /// # Errors
    /// A [`TableError`] for a capacity of 0 or below 8.
    pub fn new(
        adaptive_capacity: u32,
        static_capacity: u32,
        adaptive_probability: f32,
    ) -> Result<Self, TableError> {
        Ok(Self {
            adaptive: AdaptiveGrid::mcpg(),
            static_grid: StaticGrid::mcpg(),
            adaptive_table: HashTable::new(adaptive_capacity, 8, BucketHash::default())?,
            static_table: HashTable::new(static_capacity, 8, BucketHash::default())?,
            adaptive_probability,
        })
    }

    fn key(
        &self,
        position: Vec3,
        normal: Vec3,
        camera: Vec3,
        u: &GridUniforms,
    ) -> (GridKind, CellKey) {
        if u.grid < self.adaptive_probability {
            (
                GridKind::Adaptive,
                self.adaptive
                    .vertex_key(position, normal, camera, u.level, u.corner),
            )
        } else {
            (
                GridKind::Static,
                self.static_grid.vertex_key(position, u.corner),
            )
        }
    }

    fn table(&self, grid: GridKind) -> &HashTable<GridState> {
        match grid {
            GridKind::Adaptive => &self.adaptive_table,
            GridKind::Static => &self.static_table,
        }
    }

    fn table_mut(&mut self, grid: GridKind) -> &mut HashTable<GridState> {
        match grid {
            GridKind::Adaptive => &mut self.adaptive_table,
            GridKind::Static => &mut self.static_table,
        }
    }

    /// `grid.load(x, n)` of MCPG Alg. 1 line 5: the state at a freshly chosen vertex near
    /// `position` (the vertex's previous-frame position for the first sample of a frame, sec. 5),
    /// whether the lookup missed (the collision of line 6; always `slot.is_none()`, see
    /// [`lookup`](Self::lookup)), the grid it came from and its slot. For a whole vertex through
    /// `&self` from many threads, use [`Guide`](super::Guide).
    #[must_use]
    pub fn load(
        &self,
        position: Vec3,
        normal: Vec3,
        camera: Vec3,
        u: &GridUniforms,
    ) -> (GridState, bool, GridKind, Option<GridSlot>) {
        let (grid, key) = self.key(position, normal, camera, u);
        let table = self.table(grid);
        match table.find(&key) {
            Some(slot) => (
                table.values()[slot as usize],
                false,
                grid,
                Some(GridSlot { grid, slot }),
            ),
            None => (GridState::EMPTY, true, grid, None),
        }
    }

    /// `grid.load(x, n)` without the redundant flag of [`load`](Self::load): the state (empty
    /// when the lookup missed, the collision of Alg. 1 line 6), the grid it was chosen from and
    /// its slot (`None` exactly when the lookup missed).
    #[must_use]
    pub fn lookup(
        &self,
        position: Vec3,
        normal: Vec3,
        camera: Vec3,
        u: &GridUniforms,
    ) -> (GridState, GridKind, Option<GridSlot>) {
        let (state, _, grid, slot) = self.load(position, normal, camera, u);
        (state, grid, slot)
    }

    /// `grid.store(s)` of MCPG Alg. 3 line 12: writes `state` at a freshly chosen vertex near
    /// `position`, overwriting what that vertex held. Returns `false` when the table had no free
    /// slot within its probe limit there (the state is dropped).
    pub fn store(
        &mut self,
        position: Vec3,
        normal: Vec3,
        camera: Vec3,
        u: &GridUniforms,
        state: GridState,
    ) -> bool {
        let (grid, key) = self.key(position, normal, camera, u);
        match self.table_mut(grid).entry(&key) {
            Some((value, _)) => {
                *value = state;
                true
            }
            None => false,
        }
    }

    /// The discard heuristic's action (MCPG sec. 5): zero w̄ of the slot a state was read from.
    pub fn discard(&mut self, slot: GridSlot) {
        if let Some(state) = self
            .table_mut(slot.grid)
            .values_mut()
            .get_mut(slot.slot as usize)
        {
            state.weight_sum = 0.0;
        }
    }
}
