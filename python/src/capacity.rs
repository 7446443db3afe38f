//! The core's map at the capacities Python can choose at run time: each is its own
//! compiled `Map<VOXELS, BLOCKS, 40>`, and [`AnyMap`] is whichever one a `sndt.Map` holds.

use anyhow::Result;
use sndt_core::{Config, Map};
use sndt_host::mapping::boxed_map;

/// The 40 NYU40 classes, as the command line's maps.
pub const CLASSES: usize = 40;

/// (voxels, blocks) a map can have, smallest first: the three device capacities of
/// `sndt map --device`, then the three tiers of the host's growing map, the first of
/// which is the command line's map ([`DEFAULT`]).
pub const CAPACITIES: [(usize, usize); 6] = [
    (1024, 128),
    (4096, 512),
    (16384, 2048),
    (1 << 19, 1 << 17),
    (1 << 21, 1 << 19),
    (1 << 23, 1 << 21),
];

/// The command line's map: 2^19 voxels, 2^17 blocks (`sndt_host::mapping::HostMap`).
pub const DEFAULT: (usize, usize) = (1 << 19, 1 << 17);

/// A core map of one of the [`CAPACITIES`].
pub enum AnyMap {
    /// 1,024 voxels, 128 blocks.
    C0(Box<Map<1024, 128, CLASSES>>),
    /// 4,096 voxels, 512 blocks.
    C1(Box<Map<4096, 512, CLASSES>>),
    /// 16,384 voxels, 2,048 blocks.
    C2(Box<Map<16384, 2048, CLASSES>>),
    /// 2^19 voxels, 2^17 blocks.
    C3(Box<Map<{ 1 << 19 }, { 1 << 17 }, CLASSES>>),
    /// 2^21 voxels, 2^19 blocks.
    C4(Box<Map<{ 1 << 21 }, { 1 << 19 }, CLASSES>>),
    /// 2^23 voxels, 2^21 blocks.
    C5(Box<Map<{ 1 << 23 }, { 1 << 21 }, CLASSES>>),
}

/// `$body` with `$m` bound to the core map inside `$map` (an `AnyMap`, `&AnyMap` or
/// `&mut AnyMap`).
#[macro_export]
macro_rules! each_map {
    ($map:expr, $m:ident => $body:expr) => {
        match $map {
            $crate::capacity::AnyMap::C0($m) => $body,
            $crate::capacity::AnyMap::C1($m) => $body,
            $crate::capacity::AnyMap::C2($m) => $body,
            $crate::capacity::AnyMap::C3($m) => $body,
            $crate::capacity::AnyMap::C4($m) => $body,
            $crate::capacity::AnyMap::C5($m) => $body,
        }
    };
}

impl AnyMap {
    /// An empty map of `capacity`, one of [`CAPACITIES`] (else `None`). The config must
    /// be valid (`Config::validate`).
    pub fn new(capacity: (usize, usize), config: Config) -> Option<Result<AnyMap>> {
        let e = |e: sndt_core::Error| anyhow::anyhow!("{e}");
        let map = match CAPACITIES.iter().position(|&c| c == capacity)? {
            0 => boxed_map(config).map(AnyMap::C0),
            1 => boxed_map(config).map(AnyMap::C1),
            2 => boxed_map(config).map(AnyMap::C2),
            3 => boxed_map(config).map(AnyMap::C3),
            4 => boxed_map(config).map(AnyMap::C4),
            _ => boxed_map(config).map(AnyMap::C5),
        };
        Some(map.map_err(e))
    }

    /// (voxels, blocks) this map has room for.
    pub fn capacity(&self) -> (usize, usize) {
        match self {
            AnyMap::C0(_) => CAPACITIES[0],
            AnyMap::C1(_) => CAPACITIES[1],
            AnyMap::C2(_) => CAPACITIES[2],
            AnyMap::C3(_) => CAPACITIES[3],
            AnyMap::C4(_) => CAPACITIES[4],
            AnyMap::C5(_) => CAPACITIES[5],
        }
    }

    /// Bytes of memory the map holds (its fixed size).
    pub fn memory_bytes(&self) -> usize {
        each_map!(self, m => core::mem::size_of_val(m.as_ref()))
    }

    /// The config.
    pub fn config(&self) -> Config {
        each_map!(self, m => *m.config())
    }

    /// The snapshot image, as `sndt map --save-maps` writes it.
    pub fn snapshot(&self) -> Result<Vec<u8>, sndt_core::Error> {
        each_map!(self, m => {
            let mut buf = vec![0u8; m.snapshot_len()];
            let n = m.write_snapshot(&mut buf)?;
            buf.truncate(n);
            Ok(buf)
        })
    }

    /// Merges `other` into this map: nothing changes on an error.
    pub fn merge(&mut self, other: &AnyMap) -> Result<(), sndt_core::Error> {
        each_map!(self, m => each_map!(other, o => m.merge(o.as_ref())))
    }
}

/// The capacity `voxels` and `blocks` ask for: both given, one of [`CAPACITIES`]; one
/// given, the capacity with that many; neither, `fallback`. `Err` says what is offered.
pub fn choose(
    voxels: Option<usize>,
    blocks: Option<usize>,
    fallback: (usize, usize),
) -> Result<(usize, usize), String> {
    let found = match (voxels, blocks) {
        (None, None) => Some(fallback),
        (Some(v), None) => CAPACITIES.iter().copied().find(|c| c.0 == v),
        (None, Some(b)) => CAPACITIES.iter().copied().find(|c| c.1 == b),
        (Some(v), Some(b)) => CAPACITIES.iter().copied().find(|&c| c == (v, b)),
    };
    found.ok_or_else(|| {
        let offered: Vec<String> = CAPACITIES
            .iter()
            .map(|(v, b)| format!("voxels={v}, blocks={b}"))
            .collect();
        format!(
            "no map of voxels={}, blocks={}; the capacities offered are: {}",
            voxels.map_or("any".into(), |v| v.to_string()),
            blocks.map_or("any".into(), |b| b.to_string()),
            offered.join("; ")
        )
    })
}
