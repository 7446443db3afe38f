//! What the map holds and how it is stored: the fixed-capacity table, occupancy blocks,
//! surface voxels and their vote sampling, records (one block or voxel in the snapshot's
//! layout), the [`Map`](crate::Map) type with its queries, snapshots, merging, and the
//! framed record stream that carries spilled records over a byte link.

pub(crate) mod table;

pub(crate) mod block;
pub(crate) mod voxel;

pub(crate) mod votes;

pub(crate) mod record;

pub(crate) mod map;

pub(crate) mod snapshot;

pub(crate) mod merge;

pub(crate) mod stream;
