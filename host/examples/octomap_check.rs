//! sndt's side of the OctoMap check (`scripts/octomap.sh`): queries a map snapshot at the
//! centre of every leaf that liboctomap read from sndt's export
//! (`scripts/octomap/check_octomap.cpp` lists them) and compares.
//!
//! `cargo run -p sndt-host --example octomap_check -- MAP.sndt LEAVES.txt`
//!
//! A leaf agrees when it is one voxel (depth 16), its centre lies in a voxel that sndt's
//! `Map::occupancy` calls occupied or free as OctoMap's `isNodeOccupied` does, and no other
//! leaf lies in the same voxel. For a ColorOcTree (leaves with a colour) it must also carry
//! sndt's log-odds of that voxel and its class colour (white when free or unclassified).
//! Exits with 1 on any disagreement, or when the leaves are not as many as sndt's known
//! voxels (leaves are distinct known voxels, so equal counts mean every known voxel is a
//! leaf).
use anyhow::{bail, Context, Result};
use sndt_core::Occupancy;
use sndt_host::dataset::classes::color;
use sndt_host::eval::evaluate::load_snapshot;
use sndt_host::mapping::HostMap;
use std::collections::HashSet;

/// One leaf as check_octomap.cpp lists it.
struct Leaf {
    center: [f32; 3],
    depth: u32,
    occupied: bool,
    log_odds: f32,
    color: Option<[u8; 3]>,
}

fn parse(line: &str) -> Result<Leaf> {
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() != 6 && f.len() != 9 {
        bail!("{} fields", f.len());
    }
    let num = |i: usize| f[i].parse::<f64>();
    Ok(Leaf {
        center: [num(0)? as f32, num(1)? as f32, num(2)? as f32],
        depth: f[3].parse()?,
        occupied: f[4] == "1",
        log_odds: num(5)? as f32,
        color: if f.len() == 9 {
            Some([f[6].parse()?, f[7].parse()?, f[8].parse()?])
        } else {
            None
        },
    })
}

/// Counts of the comparison.
#[derive(Default)]
struct Tally {
    leaves: usize,
    occupied: usize,
    agree: usize,
    disagree: usize,
    colored: usize,
    first: Option<String>,
}

/// Compares one leaf with the map; `seen` holds the voxels of the leaves before it.
fn compare(map: &HostMap, leaf: &Leaf, seen: &mut HashSet<sndt_core::VoxelKey>) -> Result<()> {
    let key = map
        .voxel_key(&leaf.center)
        .context("centre outside sndt's key range")?;
    if leaf.depth != 16 {
        bail!("depth {}, not one voxel", leaf.depth);
    }
    if !seen.insert(key) {
        bail!("a second leaf in voxel {key:?}");
    }
    let state = map.occupancy(&key);
    let expected = match state {
        Occupancy::Occupied => true,
        Occupancy::Free => false,
        Occupancy::Unknown => bail!("voxel {key:?} is unknown to sndt"),
    };
    if leaf.occupied != expected {
        bail!(
            "occupied {} but sndt says {state:?} at {key:?}",
            leaf.occupied
        );
    }
    if let Some(c) = leaf.color {
        let class = (state == Occupancy::Occupied)
            .then(|| map.class(&key))
            .flatten();
        let want = class.map_or([255; 3], |(k, _)| color(k));
        if c != want || leaf.log_odds != map.log_odds(&key) {
            bail!(
                "colour {c:?} log-odds {} but sndt has {want:?} {} at {key:?}",
                leaf.log_odds,
                map.log_odds(&key)
            );
        }
    }
    Ok(())
}

fn main() {
    // One line on failure, no backtrace: the script's output is read by people.
    if let Err(e) = run() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [snapshot, leaves] = args.as_slice() else {
        bail!("usage: octomap_check MAP.sndt LEAVES.txt");
    };
    let map = load_snapshot(std::path::Path::new(snapshot))?;
    let text = std::fs::read_to_string(leaves).with_context(|| format!("reading {leaves}"))?;
    let mut t = Tally::default();
    let mut seen = HashSet::new();
    for (n, line) in text.lines().enumerate() {
        let leaf = parse(line).with_context(|| format!("{leaves}:{}", n + 1))?;
        t.leaves += 1;
        t.occupied += usize::from(leaf.occupied);
        t.colored += usize::from(leaf.color.is_some());
        match compare(&map, &leaf, &mut seen) {
            Ok(()) => t.agree += 1,
            Err(e) => {
                t.disagree += 1;
                t.first.get_or_insert(format!("line {}: {e}", n + 1));
            }
        }
    }
    let known = map.cells().count();
    let known_occupied = map.cells().filter(|(_, l)| *l > 0.0).count();
    let what = if t.colored > 0 {
        "state, log-odds and colour"
    } else {
        "state"
    };
    println!(
        "{leaves}: {} leaves ({} occupied, {} free); sndt: {known} known voxels ({known_occupied} \
         occupied, {} free); {what} agree at {}, disagree at {}",
        t.leaves,
        t.occupied,
        t.leaves - t.occupied,
        known - known_occupied,
        t.agree,
        t.disagree
    );
    if let Some(first) = t.first {
        bail!(
            "{} leaves disagree with sndt, the first: {first}",
            t.disagree
        );
    }
    if t.leaves != known {
        bail!("{} leaves but {known} known voxels", t.leaves);
    }
    Ok(())
}
