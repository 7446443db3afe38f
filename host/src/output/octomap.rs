//! The map's occupancy layer as an OctoMap, for MoveIt, octomap_server and octovis: the
//! binary tree (`.bt`, what `octomap::OcTree::readBinary` reads: free or occupied per leaf)
//! or the full `ColorOcTree` (`.ot`, what `octomap::AbstractOcTree::read` reads: each
//! node's log-odds and colour, here the colour of the voxel's semantic class).
//!
//! **Keys.** OctoMap keys the voxel of edge `res` holding a coordinate by
//! `floor(coord / res) + 32768` per axis, in a tree 16 levels deep; sndt keys it by
//! `floor(coord / h)` ([`VoxelKey`], components within ±32767). With `res = h`, the sndt
//! key `k` is the OctoMap key `k + 32768` (1..=65535), and the leaf's centre
//! `(k + 0.5) res` lies in the middle of sndt's voxel `k`. So every known sndt voxel (free
//! or occupied, log-odds not 0) becomes exactly one leaf at depth 16, and unknown voxels are
//! left out (what OctoMap calls unknown).
//!
//! **Tree.** The leaves sorted by their Morton code (the key bits interleaved from the top,
//! x lowest, which is OctoMap's child index `x + 2y + 4z` at every level) are the tree in
//! depth-first order, so one pass over the sorted leaves writes it. The tree is not pruned:
//! each leaf stays one sndt voxel, which is what the liboctomap check in
//! `scripts/octomap.sh` compares voxel by voxel; OctoMap reads unpruned trees as they are.
//!
//! **Format** (OctoMap 1.9, `OccupancyOcTreeBase::writeBinaryNode` and
//! `OcTreeBaseImpl::writeNodesRecurs`): a text header (`id`, `size` = number of nodes,
//! `res`, `data`), then the nodes depth-first from the root. Binary: per inner node two
//! bytes, 2 bits per child (0 unknown, 1 free leaf, 2 occupied leaf, 3 inner node; child
//! `i` at bits `2i` of the 16-bit little-endian word), children in index order. Full: per
//! node its value (`f32` log-odds), for a `ColorOcTree` its colour (r, g, b bytes), then a
//! byte with bit `i` set when child `i` exists. Numbers are little-endian, as liboctomap
//! writes them on x86 and ARM.

use crate::dataset::classes::color;
use anyhow::{bail, Result};
use sndt_core::{Map, VoxelKey};
use std::path::Path;

/// Levels of an OctoMap tree: leaves are at this depth, keys have this many bits.
pub const TREE_DEPTH: u32 = 16;
/// What OctoMap adds to `floor(coord / res)` to key a voxel (`tree_max_val`).
pub const KEY_OFFSET: i32 = 32768;
/// First line of a binary tree file (`.bt`).
pub const BINARY_HEADER: &str = "# Octomap OcTree binary file";
/// First line of a full tree file (`.ot`).
pub const FULL_HEADER: &str = "# Octomap OcTree file";
/// The colour a `ColorOcTreeNode` has when none was set (OctoMap's `isColorSet` is false
/// for pure white): voxels without a class.
pub const NO_COLOR: [u8; 3] = [255, 255, 255];

/// One leaf of the tree: a known sndt voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leaf {
    /// OctoMap key per axis (the sndt key plus [`KEY_OFFSET`]).
    pub key: [u16; 3],
    /// sndt's occupancy log-odds (natural units, as OctoMap's): above 0 occupied, below 0
    /// free.
    pub log_odds: f32,
    /// The colour of the voxel's class in sndt's palette, or [`NO_COLOR`].
    pub color: [u8; 3],
}

impl Leaf {
    /// Whether OctoMap counts the leaf occupied (`isNodeOccupied`: log-odds at or above
    /// its threshold, 0); a known sndt voxel never has log-odds 0.
    pub fn occupied(&self) -> bool {
        self.log_odds >= 0.0
    }
}

/// The OctoMap key of an sndt voxel (every valid [`VoxelKey`] has one).
///
/// ```
/// use sndt_host::output::octomap::octomap_key;
/// assert_eq!(octomap_key(&sndt_core::VoxelKey { x: 0, y: -1, z: 32767 }), [32768, 32767, 65535]);
/// ```
pub fn octomap_key(k: &VoxelKey) -> [u16; 3] {
    [k.x, k.y, k.z].map(|c| (i32::from(c) + KEY_OFFSET) as u16)
}

/// Centre of the leaf with OctoMap key `key` at depth 16 (OctoMap's `keyToCoord`), metres.
///
/// ```
/// use sndt_host::output::octomap::key_center;
/// assert_eq!(key_center([32768, 32767, 32770], 0.5), [0.25, -0.25, 1.25]);
/// ```
pub fn key_center(key: [u16; 3], resolution: f64) -> [f64; 3] {
    key.map(|k| (f64::from(i32::from(k) - KEY_OFFSET) + 0.5) * resolution)
}

/// The resolution written for an sndt cell size: the shortest decimal that reads back as
/// the `f32` (0.1, not 0.100000001490116), as OctoMap itself prints a resolution set to
/// 0.1. The difference to the `f32` is a few parts in 10^8 of a voxel, so leaf centres stay
/// in the middle of sndt's voxels.
pub fn resolution_of(cell_size: f32) -> f64 {
    format!("{cell_size}")
        .parse()
        .unwrap_or(f64::from(cell_size))
}

/// OctoMap's child index of a key at key bit `bit` (`computeChildIdx`: x 1, y 2, z 4).
fn child_index(key: [u16; 3], bit: u32) -> usize {
    key.iter()
        .enumerate()
        .map(|(axis, k)| (usize::from(*k >> bit) & 1) << axis)
        .sum()
}

/// The Morton code of a key: its child indices from the root down, 3 bits each.
fn morton(key: [u16; 3]) -> u64 {
    (0..TREE_DEPTH)
        .rev()
        .fold(0, |code, bit| code << 3 | child_index(key, bit) as u64)
}

/// The leaves of a node at `depth` (sorted by Morton code) split by child, in index order.
fn children(leaves: &[Leaf], depth: u32) -> [&[Leaf]; 8] {
    let bit = TREE_DEPTH - 1 - depth;
    let mut out = [&leaves[..0]; 8];
    let mut rest = leaves;
    for (i, slot) in out.iter_mut().enumerate() {
        // The leaves of one node share the key bits above `bit`, so their child indices at
        // `bit` are sorted too.
        let n = rest.partition_point(|l| child_index(l.key, bit) <= i);
        (*slot, rest) = rest.split_at(n);
    }
    out
}

/// A serialised tree: the bytes after the header's `data` line and the number of nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Encoded {
    /// The tree, root first (empty for an empty tree).
    pub bytes: Vec<u8>,
    /// Nodes: root, inner nodes and leaves (the header's `size`).
    pub nodes: usize,
}

/// An OctoMap tree of an sndt map's known voxels, not pruned.
#[derive(Clone, Debug, PartialEq)]
pub struct OctoMap {
    resolution: f64,
    leaves: Vec<Leaf>,
}

impl OctoMap {
    /// The tree of every known voxel of `map` at the map's cell size: occupied and free
    /// as [`Map::occupancy`] classifies them, coloured by [`Map::class`] in sndt's palette
    /// ([`color`]) when occupied and classified, [`NO_COLOR`] otherwise.
    pub fn from_map<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) -> OctoMap {
        let leaves = map.cells().map(|(key, log_odds)| {
            let class = (log_odds > 0.0).then(|| map.class(&key)).flatten();
            Leaf {
                key: octomap_key(&key),
                log_odds,
                color: class.map_or(NO_COLOR, |(c, _)| color(c)),
            }
        });
        let resolution = resolution_of(map.config().cell_size);
        // The map's cells are unique, so this cannot fail.
        OctoMap::from_leaves(resolution, leaves.collect()).unwrap_or(OctoMap {
            resolution,
            leaves: Vec::new(),
        })
    }

    /// A tree of the given leaves at `resolution` metres; fails on a repeated key, a
    /// resolution that is not positive or a leaf with log-odds 0 (unknown, not a leaf).
    pub fn from_leaves(resolution: f64, mut leaves: Vec<Leaf>) -> Result<OctoMap> {
        if !(resolution > 0.0 && resolution.is_finite()) {
            bail!("OctoMap resolution {resolution}: must be positive");
        }
        if let Some(l) = leaves.iter().find(|l| l.log_odds == 0.0) {
            bail!("OctoMap leaf {:?}: log-odds 0 is unknown", l.key);
        }
        leaves.sort_unstable_by_key(|l| morton(l.key));
        if let Some(w) = leaves.windows(2).find(|w| w[0].key == w[1].key) {
            bail!("OctoMap leaf {:?} given twice", w[0].key);
        }
        Ok(OctoMap { resolution, leaves })
    }

    /// Edge of a leaf, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The leaves in the tree's depth-first order.
    pub fn leaves(&self) -> &[Leaf] {
        &self.leaves
    }

    /// Leaves OctoMap counts occupied.
    pub fn occupied(&self) -> usize {
        self.leaves.iter().filter(|l| l.occupied()).count()
    }

    /// The binary tree (free / occupied only), as `OcTree::writeBinaryData` writes it and
    /// an `octomap_msgs/msg/Octomap` with `binary: true` carries it.
    pub fn binary_data(&self) -> Encoded {
        let mut bytes = Vec::new();
        let nodes = if self.leaves.is_empty() {
            0
        } else {
            binary_node(&self.leaves, 0, &mut bytes)
        };
        Encoded { bytes, nodes }
    }

    /// The full tree of a `ColorOcTree` (`writeData`): every node's log-odds and colour.
    /// An inner node holds what OctoMap's `updateInnerOccupancy` gives it: the largest
    /// log-odds of its children and the mean colour of its coloured children.
    pub fn color_data(&self) -> Encoded {
        let mut bytes = Vec::new();
        let nodes = if self.leaves.is_empty() {
            0
        } else {
            full_node(&self.leaves, 0, &mut bytes).nodes
        };
        Encoded { bytes, nodes }
    }

    /// A whole `.bt` file: header and [`OctoMap::binary_data`].
    pub fn binary_file(&self) -> Vec<u8> {
        self.file(BINARY_HEADER, "OcTree", self.binary_data()).0
    }

    /// A whole `.ot` file of a `ColorOcTree`: header and [`OctoMap::color_data`].
    pub fn color_file(&self) -> Vec<u8> {
        self.file(FULL_HEADER, "ColorOcTree", self.color_data()).0
    }

    /// The header OctoMap's readers parse (`AbstractOcTree::readHeader`: `#` lines are
    /// comments, then `id`, `size`, `res`, and `data` ends it), then the tree; and the
    /// tree's nodes.
    fn file(&self, first_line: &str, id: &str, tree: Encoded) -> (Vec<u8>, usize) {
        let mut out = format!(
            "{first_line}\n# sndt occupancy layer: one leaf per known voxel, not pruned\n\
             id {id}\nsize {}\nres {}\ndata\n",
            tree.nodes, self.resolution
        )
        .into_bytes();
        out.extend_from_slice(&tree.bytes);
        (out, tree.nodes)
    }
}

/// Writes the binary node at `depth` holding `leaves` (not empty) and its inner
/// descendants; returns the nodes of its subtree, itself included.
fn binary_node(leaves: &[Leaf], depth: u32, out: &mut Vec<u8>) -> usize {
    let kids = children(leaves, depth);
    let last = depth + 1 == TREE_DEPTH;
    let mut word = 0u16;
    for (i, kid) in kids.iter().enumerate() {
        let code: u16 = match kid {
            [] => 0b00,
            [leaf] if last && leaf.occupied() => 0b10,
            [_] if last => 0b01,
            _ => 0b11,
        };
        word |= code << (2 * i);
    }
    out.extend_from_slice(&word.to_le_bytes());
    let mut nodes = 1;
    for kid in kids.iter().filter(|k| !k.is_empty()) {
        nodes += if last {
            1
        } else {
            binary_node(kid, depth + 1, out)
        };
    }
    nodes
}

/// What [`full_node`] tells its parent.
struct Subtree {
    nodes: usize,
    log_odds: f32,
    color: [u8; 3],
}

/// Writes the full node at `depth` holding `leaves` (not empty) and all its descendants.
fn full_node(leaves: &[Leaf], depth: u32, out: &mut Vec<u8>) -> Subtree {
    if depth == TREE_DEPTH {
        let leaf = leaves[0];
        write_full(out, leaf.log_odds, leaf.color, 0);
        return Subtree {
            nodes: 1,
            log_odds: leaf.log_odds,
            color: leaf.color,
        };
    }
    // The node's value and colour depend on its children, written after it: reserve its
    // bytes and fill them in once the children are known.
    let at = out.len();
    write_full(out, 0.0, NO_COLOR, 0);
    let (mut nodes, mut mask, mut max) = (1, 0u8, f32::NEG_INFINITY);
    let (mut sum, mut colored) = ([0u32; 3], 0u32);
    for (i, kid) in children(leaves, depth).iter().enumerate() {
        if kid.is_empty() {
            continue;
        }
        mask |= 1 << i;
        let sub = full_node(kid, depth + 1, out);
        nodes += sub.nodes;
        max = max.max(sub.log_odds);
        if sub.color != NO_COLOR {
            colored += 1;
            for (s, c) in sum.iter_mut().zip(sub.color) {
                *s += u32::from(c);
            }
        }
    }
    // OctoMap's getAverageChildColor: integer mean of the coloured children, white if none.
    let color = if colored == 0 {
        NO_COLOR
    } else {
        sum.map(|s| (s / colored) as u8)
    };
    let mut node = Vec::with_capacity(8);
    write_full(&mut node, max, color, mask);
    out[at..at + 8].copy_from_slice(&node);
    Subtree {
        nodes,
        log_odds: max,
        color,
    }
}

/// One `ColorOcTreeNode` as `writeData` and the child mask write it: 8 bytes.
fn write_full(out: &mut Vec<u8>, log_odds: f32, color: [u8; 3], mask: u8) {
    out.extend_from_slice(&log_odds.to_le_bytes());
    out.extend_from_slice(&color);
    out.push(mask);
}

/// The kinds of OctoMap file [`write_octomap`] writes, by the path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OctoFormat {
    /// `.bt`: an `OcTree` binary tree, free / occupied per leaf.
    Binary,
    /// `.ot`: a `ColorOcTree` with log-odds and class colours.
    Color,
}

impl OctoFormat {
    /// The format a path's extension asks for: `.bt` or `.ot`, else an error.
    pub fn of(path: &Path) -> Result<OctoFormat> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("bt") => Ok(OctoFormat::Binary),
            Some("ot") => Ok(OctoFormat::Color),
            _ => bail!(
                "{}: an OctoMap file ends in .bt (binary OcTree) or .ot (ColorOcTree)",
                path.display()
            ),
        }
    }
}

/// Writes `tree` to `path` as the extension says (`.bt` binary `OcTree`, `.ot`
/// `ColorOcTree`, see [`OctoFormat::of`]), atomically. Returns the format and the number of
/// nodes written (the header's `size`).
///
/// ```
/// use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Map, Point3};
/// use sndt_host::output::octomap::{write_octomap, OctoFormat, OctoMap};
/// // One ray from the origin up to a surface 1 m away: 10 free voxels, then the surface.
/// let mut map: Map<16, 64, 2> = Map::new(Config::DEFAULT);
/// let p = [LabeledPoint::new(Point3::new(0.0, 0.0, 1.0), Labels::top1(1))];
/// map.integrate(&Isometry3::identity(), &p).unwrap();
/// let tree = OctoMap::from_map(&map);
/// assert_eq!((tree.leaves().len(), tree.occupied()), (11, 1));
/// let path = std::env::temp_dir().join(format!("sndt-doc-{}.bt", std::process::id()));
/// // Voxels (0, 0, 0..=10) share the nodes from the root down to depth 12 (13), then split
/// // into 2, 3 and 6 nodes at depths 13, 14 and 15 (z bits 3, 2, 1), then 11 leaves.
/// assert_eq!(write_octomap(&path, &tree).unwrap(), (OctoFormat::Binary, 13 + 11 + 11));
/// let bytes = std::fs::read(&path).unwrap();
/// assert!(bytes.starts_with(b"# Octomap OcTree binary file\n"));
/// let text = String::from_utf8_lossy(&bytes);
/// assert!(text.contains("\nid OcTree\n") && text.contains("\nres 0.1\ndata\n"));
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_octomap(path: &Path, tree: &OctoMap) -> Result<(OctoFormat, usize)> {
    let format = OctoFormat::of(path)?;
    let (bytes, nodes) = match format {
        OctoFormat::Binary => tree.file(BINARY_HEADER, "OcTree", tree.binary_data()),
        OctoFormat::Color => tree.file(FULL_HEADER, "ColorOcTree", tree.color_data()),
    };
    crate::atomic::write_bytes(path, bytes)?;
    Ok((format, nodes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sndt_core::{Config, Isometry3, LabeledPoint, Labels, Occupancy, Point3};

    /// OctoMap key of the sndt key `k` (the offset spelled out, not [`octomap_key`]).
    fn key(k: [i32; 3]) -> [u16; 3] {
        k.map(|c| (c + 32768) as u16)
    }

    fn leaf(k: [i32; 3], log_odds: f32, color: [u8; 3]) -> Leaf {
        Leaf {
            key: key(k),
            log_odds,
            color,
        }
    }

    /// `n` copies of a two-byte node.
    fn repeat(word: [u8; 2], n: usize) -> Vec<u8> {
        word.repeat(n)
    }

    #[test]
    fn one_occupied_voxel_is_sixteen_inner_nodes() {
        // sndt (0, 0, 0) is OctoMap key 0x8000 on every axis: the root's child 7 (top bit
        // set on x, y and z), then child 0 fourteen times, then the occupied leaf (code 2)
        // as child 0 of the node at depth 15.
        let tree = OctoMap::from_leaves(0.1, vec![leaf([0, 0, 0], 0.85, NO_COLOR)]).unwrap();
        let mut data = vec![0x00, 0xC0];
        data.extend(repeat([0x03, 0x00], 14));
        data.extend([0x02, 0x00]);
        assert_eq!(
            tree.binary_data(),
            Encoded {
                bytes: data.clone(),
                nodes: 17
            }
        );
        let mut file = b"# Octomap OcTree binary file\n\
            # sndt occupancy layer: one leaf per known voxel, not pruned\n\
            id OcTree\nsize 17\nres 0.1\ndata\n"
            .to_vec();
        file.extend(data);
        assert_eq!(tree.binary_file(), file);
    }

    #[test]
    fn a_free_voxel_below_zero_takes_the_other_branch() {
        // sndt x = -1 is OctoMap 0x7FFF: top bit clear, all others set. Root: child 6
        // (y, z) inner, bits 12-13 = 0x30 in the high byte; then child 1 (x) inner, code 3
        // at bits 2-3 = 0x0C; the free leaf is code 1 at bits 2-3 = 0x04.
        let tree = OctoMap::from_leaves(0.1, vec![leaf([-1, 0, 0], -0.4, NO_COLOR)]).unwrap();
        let mut data = vec![0x00, 0x30];
        data.extend(repeat([0x0C, 0x00], 14));
        data.extend([0x04, 0x00]);
        assert_eq!(tree.binary_data().bytes, data);
        assert_eq!(tree.occupied(), 0);
    }

    #[test]
    fn two_branches_are_written_depth_first_in_child_order() {
        // Given in the other order: the tree sorts them. Child 6 (the free voxel) before 7.
        let leaves = vec![
            leaf([0, 0, 0], 0.85, NO_COLOR),
            leaf([-1, 0, 0], -0.4, NO_COLOR),
        ];
        let tree = OctoMap::from_leaves(0.05, leaves).unwrap();
        let mut data = vec![0x00, 0xF0];
        data.extend(repeat([0x0C, 0x00], 14));
        data.extend([0x04, 0x00]);
        data.extend(repeat([0x03, 0x00], 14));
        data.extend([0x02, 0x00]);
        assert_eq!(
            tree.binary_data(),
            Encoded {
                bytes: data,
                nodes: 33
            }
        );
    }

    #[test]
    fn eight_siblings_fill_both_bytes() {
        // The 2x2x2 voxels from (0, 0, 0): children 0..7 of one node at depth 15, child
        // index x + 2y + 4z. Even children occupied (code 2), odd free (code 1): each byte
        // is 01 10 01 10 = 0x66.
        let mut leaves = Vec::new();
        for i in 0..8 {
            let k = [i & 1, (i >> 1) & 1, (i >> 2) & 1];
            let l = if i % 2 == 0 { 1.0 } else { -1.0 };
            leaves.push(leaf(k, l, NO_COLOR));
        }
        let tree = OctoMap::from_leaves(0.1, leaves).unwrap();
        let mut data = vec![0x00, 0xC0];
        data.extend(repeat([0x03, 0x00], 14));
        data.extend([0x66, 0x66]);
        assert_eq!(
            tree.binary_data(),
            Encoded {
                bytes: data,
                nodes: 24
            }
        );
        assert_eq!((tree.leaves().len(), tree.occupied()), (8, 4));
    }

    #[test]
    fn the_color_tree_holds_values_colours_and_child_masks() {
        // One occupied voxel: 17 nodes of 8 bytes (f32 0.5 = 00 00 00 3F, r g b, mask);
        // the root's only child is 7, every inner node below has child 0, the leaf none.
        let red = [128, 0, 0];
        let tree = OctoMap::from_leaves(0.1, vec![leaf([0, 0, 0], 0.5, red)]).unwrap();
        let node = |mask: u8| [0x00, 0x00, 0x00, 0x3F, 128, 0, 0, mask];
        let mut data = node(0x80).to_vec();
        for _ in 0..15 {
            data.extend(node(0x01));
        }
        data.extend(node(0x00));
        assert_eq!(
            tree.color_data(),
            Encoded {
                bytes: data,
                nodes: 17
            }
        );
        let file = tree.color_file();
        let head = b"# Octomap OcTree file\n# sndt occupancy layer: one leaf per known voxel, not pruned\nid ColorOcTree\nsize 17\nres 0.1\ndata\n";
        assert!(file.starts_with(head) && file.len() == head.len() + 17 * 8);
    }

    #[test]
    fn an_inner_node_has_the_largest_value_and_the_mean_colour() {
        // Three children of the node at depth 15: red 0.5, green 1.0 and a free voxel
        // without colour. The node (and so every node above it): value 1.0 (00 00 80 3F),
        // colour (128 / 2, 128 / 2, 0), mask 0b111 at depth 15.
        let leaves = vec![
            leaf([0, 0, 0], 0.5, [128, 0, 0]),
            leaf([1, 0, 0], 1.0, [0, 128, 0]),
            leaf([0, 1, 0], -0.4, NO_COLOR),
        ];
        let data = OctoMap::from_leaves(0.1, leaves).unwrap().color_data();
        assert_eq!(data.nodes, 19);
        assert_eq!(data.bytes[..8], [0x00, 0x00, 0x80, 0x3F, 64, 64, 0, 0x80]);
        assert_eq!(
            data.bytes[15 * 8..16 * 8],
            [0x00, 0x00, 0x80, 0x3F, 64, 64, 0, 0x07]
        );
        // The free leaf, last: -0.4 and white.
        let last = &data.bytes[18 * 8..];
        assert_eq!(last[..4], (-0.4f32).to_le_bytes());
        assert_eq!(last[4..], [255, 255, 255, 0]);
    }

    #[test]
    fn the_key_range_ends_map_to_octomap_keys_one_and_65535() {
        let lo = VoxelKey {
            x: -32767,
            y: 0,
            z: 32767,
        };
        assert_eq!(octomap_key(&lo), [1, 32768, 65535]);
        let c = key_center(octomap_key(&lo), 0.1);
        let back = VoxelKey::from_point(&c.map(|v| v as f32), 0.1);
        assert_eq!(back, Some(lo));
        assert_eq!(resolution_of(0.1), 0.1);
        assert_eq!(resolution_of(0.05), 0.05);
    }

    #[test]
    fn bad_leaves_and_paths_are_refused() {
        let twice = vec![
            leaf([1, 2, 3], 1.0, NO_COLOR),
            leaf([1, 2, 3], -1.0, NO_COLOR),
        ];
        assert!(OctoMap::from_leaves(0.1, twice).is_err());
        assert!(OctoMap::from_leaves(0.1, vec![leaf([0, 0, 0], 0.0, NO_COLOR)]).is_err());
        assert!(OctoMap::from_leaves(0.0, Vec::new()).is_err());
        let empty = OctoMap::from_leaves(0.1, Vec::new()).unwrap();
        assert_eq!(
            empty.binary_data(),
            Encoded {
                bytes: Vec::new(),
                nodes: 0
            }
        );
        assert!(String::from_utf8_lossy(&empty.binary_file()).ends_with("size 0\nres 0.1\ndata\n"));
        assert_eq!(
            OctoFormat::of(Path::new("a/m.bt")).unwrap(),
            OctoFormat::Binary
        );
        assert_eq!(
            OctoFormat::of(Path::new("m.ot")).unwrap(),
            OctoFormat::Color
        );
        assert!(OctoFormat::of(Path::new("m.octomap")).is_err());
    }

    #[test]
    fn every_known_voxel_of_a_map_is_one_leaf_in_its_own_voxel() {
        // A fan of rays onto a wall 1.5 m away, class 3.
        let mut map: Map<256, 256, 4> = Map::new(Config::with_cell_size(0.1));
        let points: Vec<LabeledPoint> = (0..40)
            .map(|i| {
                let (x, y) = ((i % 8) as f32 * 0.1 - 0.35, (i / 8) as f32 * 0.1 - 0.2);
                LabeledPoint::new(Point3::new(x, y, 1.5), Labels::top1(3))
            })
            .collect();
        for _ in 0..3 {
            map.integrate(&Isometry3::identity(), &points).unwrap();
        }
        let tree = OctoMap::from_map(&map);
        assert_eq!(tree.leaves().len(), map.cells().count());
        assert!(tree.occupied() > 0 && tree.occupied() < tree.leaves().len());
        for l in tree.leaves() {
            let c = key_center(l.key, tree.resolution()).map(|v| v as f32);
            let k = map.voxel_key(&c).unwrap();
            let occupied = map.occupancy(&k) == Occupancy::Occupied;
            assert_eq!(l.occupied(), occupied, "{k:?}");
            assert_eq!(l.log_odds, map.log_odds(&k));
            let expected = if occupied { color(3) } else { NO_COLOR };
            assert_eq!(l.color, expected, "{k:?}");
        }
    }
}
