//! What the map holds and how it is stored: the fixed-capacity table, occupancy blocks,
//! surface voxels and their vote sampling, the [`Map`](crate::Map) type with its queries,
//! and snapshots.

pub(crate) mod table;

pub(crate) mod block;
pub(crate) mod voxel;

pub(crate) mod map;
pub(crate) mod votes;

pub(crate) mod snapshot;
