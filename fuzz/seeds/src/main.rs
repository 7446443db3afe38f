//! Writes raw seed inputs for the fuzz targets into `<out>/<target>/`: snapshots and record
//! streams the core writes for a few small maps, and PNG, JSON, `.npy`, HDF5 and MCAP files the host's own
//! writers produce for small frames. `scripts/fuzz.sh --seeds` runs this and then merges
//! the result into `fuzz/corpus/` with libFuzzer's `-merge=1`, which keeps only inputs
//! that add coverage.
//!
//! Usage: `sndt-fuzz-seeds <out>` (the directory must not exist yet).

use anyhow::{bail, Context, Result};
use sndt_core::{
    Config, Depth, DepthImage, DepthKind, Isometry3, LabelImage, Map, MissModel, Pinhole, Record,
    RecordSink, StreamWriter, Translation3, UnitQuaternion, Vector3, STREAM_FRAME_BYTES,
};
use sndt_host::dataset::prepared::{write_frame, write_split_list};
use sndt_host::dataset::{Frame, FrameId, Rays, TopK};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn main() -> Result<()> {
    let Some(out) = std::env::args_os().nth(1).map(PathBuf::from) else {
        bail!("usage: sndt-fuzz-seeds <out-dir>");
    };
    if out.exists() {
        bail!("{}: exists; give a new directory", out.display());
    }
    snapshots(&out.join("snapshot"))?;
    record_streams(&out.join("record_stream"))?;
    integrate(&out.join("integrate"))?;
    prepared(&out)?;
    hdf5(&out.join("hdf5"))?;
    bag(&out.join("mcap"))?;
    Ok(())
}

fn put(dir: &Path, name: &str, bytes: &[u8]) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join(name), bytes).with_context(|| format!("writing {name}"))
}

/// An 8x6 camera looking down +z at a tilted wall 1.5 to 2.2 m away.
fn camera() -> Pinhole {
    Pinhole {
        fx: 6.0,
        fy: 6.0,
        cx: 4.0,
        cy: 3.0,
        width: 8,
        height: 6,
    }
}

fn wall(classes: u8) -> (Vec<f32>, Vec<u8>) {
    let depth = (0..48).map(|i| 1.5 + 0.015 * i as f32).collect();
    let labels = (0..48).map(|i| 1 + (i % classes as usize) as u8).collect();
    (depth, labels)
}

fn pose(x: f32, yaw: f32) -> Isometry3<f32> {
    Isometry3::from_parts(
        Translation3::new(x, 0.1, -0.2),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.0, yaw, 0.0)),
    )
}

/// The `k`-th view of the wall (planar and range depth alternate).
fn view<'a>(k: usize, depth: &'a [f32], labels: &'a [u8]) -> DepthImage<'a> {
    DepthImage {
        camera: camera(),
        depth: Depth::Metres(depth),
        kind: if k.is_multiple_of(2) {
            DepthKind::Planar
        } else {
            DepthKind::Range
        },
        labels: LabelImage::Top1(labels),
        stride: 1,
    }
}

fn view_pose(k: usize) -> Isometry3<f32> {
    pose(0.1 * k as f32, 0.2 * k as f32)
}

/// Integrates `frames` views of the wall and writes the snapshot.
fn map_snapshot<const C: usize>(config: Config, frames: usize) -> Result<Vec<u8>> {
    let mut map: Box<Map<256, 128, C>> = Box::new(Map::new(config));
    let (depth, labels) = wall(C as u8);
    for k in 0..frames {
        map.integrate_depth(&view_pose(k), &view(k, &depth, &labels))
            .map_err(|e| anyhow::anyhow!("integrate: {e:?}"))?;
    }
    let mut buf = vec![0u8; map.snapshot_len()];
    let n = map
        .write_snapshot(&mut buf)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    buf.truncate(n);
    Ok(buf)
}

fn snapshots(dir: &Path) -> Result<()> {
    let mut coarse = Config::with_cell_size(0.25);
    coarse.quant_bits = 3;
    coarse.miss_model = MissModel::Constant;
    let mut decaying = Config::DEFAULT;
    decaying.n_max = 4;
    decaying.top_k = 3;
    put(dir, "empty-c4", &map_snapshot::<4>(Config::DEFAULT, 0)?)?;
    put(dir, "wall-c1", &map_snapshot::<1>(Config::DEFAULT, 1)?)?;
    put(dir, "wall-c4", &map_snapshot::<4>(Config::DEFAULT, 1)?)?;
    put(dir, "wall-c40", &map_snapshot::<40>(Config::DEFAULT, 2)?)?;
    put(dir, "coarse-c4", &map_snapshot::<4>(coarse, 3)?)?;
    put(dir, "decayed-c4", &map_snapshot::<4>(decaying, 4)?)
}

/// A record stream as it goes over the link: the start frame for a map's config, any
/// records sent, then (`finish`) the map's records and the end frame.
struct Link {
    bytes: Vec<u8>,
    writer: StreamWriter,
}

impl Link {
    fn start<const V: usize, const B: usize, const C: usize>(map: &Map<V, B, C>) -> Result<Link> {
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        let (writer, n) =
            StreamWriter::start(map, &mut buf).map_err(|e| anyhow::anyhow!("start: {e:?}"))?;
        Ok(Link {
            bytes: buf[..n].to_vec(),
            writer,
        })
    }

    /// Sends a record; `false` (refused) if it does not fit a frame.
    fn send(&mut self, r: Record<'_>) -> bool {
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        match self.writer.record(r, &mut buf) {
            Ok(n) => {
                self.bytes.extend_from_slice(&buf[..n]);
                true
            }
            Err(_) => false,
        }
    }

    /// Sends every record of `map`, then the end frame; the fuzz input: `flags`, the link.
    fn finish<const V: usize, const B: usize, const C: usize>(
        mut self,
        map: &Map<V, B, C>,
        dropped: u32,
        flags: u8,
    ) -> Result<Vec<u8>> {
        let sent = map.write_records(&mut |r: Record<'_>| self.send(r));
        if sent.refused != 0 {
            bail!("{} records refused by the stream writer", sent.refused);
        }
        let mut buf = [0u8; STREAM_FRAME_BYTES];
        let n = self
            .writer
            .end(map, dropped, &mut buf)
            .map_err(|e| anyhow::anyhow!("end: {e:?}"))?;
        self.bytes.extend_from_slice(&buf[..n]);
        let mut input = vec![flags];
        input.extend(self.bytes);
        Ok(input)
    }
}

/// A 4x3 camera looking at a wall 0.8 m away, from `x` metres along the wall: a view small
/// enough that a record stream of a few of them stays a few KiB (libFuzzer's inputs grow
/// to the largest seed, and the target's cost to the records times the map's size).
fn near_view(k: usize, classes: u8) -> (Isometry3<f32>, Vec<f32>, Vec<u8>) {
    let depth = (0..12).map(|i| 0.8 + 0.01 * i as f32).collect();
    let labels = (0..12)
        .map(|i| 1 + ((i + k) % classes as usize) as u8)
        .collect();
    (pose(0.15 * k as f32, 0.1 * k as f32), depth, labels)
}

fn near_camera() -> Pinhole {
    Pinhole {
        fx: 4.0,
        fy: 4.0,
        cx: 2.0,
        cy: 1.5,
        width: 4,
        height: 3,
    }
}

/// Integrates near views `0..frames` into `map`, handing evicted records to `sink`.
fn near_views<const V: usize, const B: usize, const C: usize>(
    map: &mut Map<V, B, C>,
    frames: usize,
    sink: &mut dyn RecordSink,
) -> Result<(u32, u32)> {
    let (mut spilled, mut dropped) = (0, 0);
    for k in 0..frames {
        let (pose, depth, labels) = near_view(k, C as u8);
        let image = DepthImage {
            camera: near_camera(),
            ..view(k, &depth, &labels)
        };
        let report = map
            .integrate_depth_spilling(&pose, &image, sink)
            .map_err(|e| anyhow::anyhow!("integrate: {e:?}"))?;
        spilled += report.records_spilled;
        dropped += report.records_dropped;
    }
    Ok((spilled, dropped))
}

/// A map of `frames` near views, sent whole as a record stream.
fn map_stream<const C: usize>(config: Config, frames: usize, flags: u8) -> Result<Vec<u8>> {
    let mut map: Box<Map<256, 128, C>> = Box::new(Map::new(config));
    near_views(&mut *map, frames, &mut |_: Record<'_>| true)?;
    Link::start(&*map)?.finish(&*map, 0, flags)
}

/// A device-sized map (8 voxels, 4 blocks) that evicts while it integrates six near views:
/// the records it spills go on the link as they come (every third refused when `refuse`,
/// and counted as dropped), then its last map's records, so the receiver merges voxels and
/// blocks it already holds.
fn spilled_stream(refuse: bool, flags: u8) -> Result<Vec<u8>> {
    let mut map: Box<Map<8, 4, 4>> = Box::new(Map::new(Config::DEFAULT));
    let mut link = Link::start(&*map)?;
    let mut offered = 0u32;
    let (spilled, dropped) = near_views(&mut *map, 6, &mut |r: Record<'_>| {
        offered += 1;
        !(refuse && offered.is_multiple_of(3)) && link.send(r)
    })?;
    if spilled == 0 || refuse != (dropped > 0) {
        bail!("spilled stream: {spilled} records spilled, {dropped} dropped");
    }
    link.finish(&*map, dropped, flags)
}

/// Record streams (a flags byte, then the link bytes; see the target): whole maps of 1, 4
/// and 40 classes, of other configs, empty, one larger than the target's receiving map
/// (`wide`), and a small map's spilled records, with no repairs (flags 0) and with all of
/// them (flags 7).
fn record_streams(dir: &Path) -> Result<()> {
    let mut coarse = Config::with_cell_size(0.25);
    coarse.quant_bits = 3;
    coarse.miss_model = MissModel::Constant;
    let mut decaying = Config::DEFAULT;
    decaying.n_max = 4;
    decaying.top_k = 3;
    for flags in [0u8, 7] {
        let put = |name: &str, bytes: &[u8]| put(dir, &format!("{name}-flags{flags}"), bytes);
        put("empty-c4", &map_stream::<4>(Config::DEFAULT, 0, flags)?)?;
        put("near-c1", &map_stream::<1>(Config::DEFAULT, 1, flags)?)?;
        put("near-c4", &map_stream::<4>(Config::DEFAULT, 2, flags)?)?;
        put("near-c40", &map_stream::<40>(Config::DEFAULT, 2, flags)?)?;
        put("coarse-c4", &map_stream::<4>(coarse, 3, flags)?)?;
        put("decayed-c4", &map_stream::<4>(decaying, 2, flags)?)?;
        put("wide-c1", &map_stream::<1>(Config::DEFAULT, 6, flags)?)?;
        put("spilled-c4", &spilled_stream(false, flags)?)?;
        put("spilled-dropped-c4", &spilled_stream(true, flags)?)?;
    }
    Ok(())
}

/// Structured-input seeds: bytes from a fixed linear congruential generator.
fn integrate(dir: &Path) -> Result<()> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for (k, len) in [64usize, 256, 1024, 4096].into_iter().enumerate() {
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 56) as u8
            })
            .collect();
        put(dir, &format!("lcg-{k}"), &bytes)?;
    }
    put(dir, "zeros", &[0u8; 512])
}

/// A small frame of the prepared layout (depth, labels, predictions, extrinsics,
/// intrinsics, split list) written by the host's writer, then filed by target.
fn prepared(out: &Path) -> Result<()> {
    let tmp = out.join("prepared-tmp");
    let (depth, labels) = wall(40);
    let n = depth.len();
    let id = FrameId::parse("synth_00/cam_00/0003")?;
    let frame = Frame {
        id: id.clone(),
        pose: pose(0.4, 0.3),
        rays: Arc::new(Rays::Pinhole(camera())),
        depth,
        depth_kind: DepthKind::Planar,
        labels: Some(labels),
        predictions: Some(TopK {
            classes: (0..n).map(|i| [1 + (i % 40) as u8, 2, 3]).collect(),
            scores: vec![[0.6, 0.3, 0.1]; n],
        }),
    };
    write_frame(&tmp, "test", &frame)?;
    write_split_list(&tmp, "test", &[id])?;
    let split = tmp.join("test");
    let file = |kind: &str, ext: &str| {
        split
            .join(kind)
            .join("synth_00/cam_00")
            .join(format!("0003.{ext}"))
    };
    put(
        &out.join("png"),
        "depth",
        &std::fs::read(file("depth", "png"))?,
    )?;
    put(
        &out.join("png"),
        "labels",
        &std::fs::read(file("semantic_40", "png"))?,
    )?;
    put(
        &out.join("json"),
        "extrinsics",
        &std::fs::read(file("extrinsics", "json"))?,
    )?;
    let intrinsics = split.join("intrinsics/synth_00/cam_00.json");
    put(&out.join("json"), "intrinsics", &std::fs::read(intrinsics)?)?;
    put(
        &out.join("json"),
        "split-list",
        &std::fs::read(tmp.join("test.txt"))?,
    )?;
    // The npy target reads width - 1 and height - 1 from its first two bytes.
    let mut npy = vec![7u8, 5];
    npy.extend(std::fs::read(file("esanet", "npy"))?);
    put(&out.join("npy"), "topk-8x6", &npy)?;
    std::fs::remove_dir_all(&tmp)?;
    Ok(())
}

/// Small HDF5 files as Hypersim stores them: float32 depth, int16 labels (-1 void),
/// float64 keyframe orientations.
fn hdf5(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let e = |e: rust_hdf5::Hdf5Error| anyhow::anyhow!("HDF5: {e}");
    let f = rust_hdf5::H5File::create(dir.join("depth")).map_err(e)?;
    let d = f
        .new_dataset::<f32>()
        .shape([6usize, 8])
        .create("dataset")
        .map_err(e)?;
    d.write_raw(&wall(1).0).map_err(e)?;
    f.close().map_err(e)?;
    let f = rust_hdf5::H5File::create(dir.join("semantic")).map_err(e)?;
    let d = f
        .new_dataset::<i16>()
        .shape([6usize, 8])
        .create("dataset")
        .map_err(e)?;
    let labels: Vec<i16> = (0..48)
        .map(|i| if i % 7 == 0 { -1 } else { 1 + i % 40 })
        .collect();
    d.write_raw(&labels).map_err(e)?;
    f.close().map_err(e)?;
    let f = rust_hdf5::H5File::create(dir.join("orientations")).map_err(e)?;
    let d = f
        .new_dataset::<f64>()
        .shape([2usize, 3, 3])
        .create("dataset")
        .map_err(e)?;
    let eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    d.write_raw(&[eye, eye].concat()).map_err(e)?;
    f.close().map_err(e)?;
    Ok(())
}

/// Two frames of the wall as a ROS 2 bag (depth, labels, camera info, /tf).
fn bag(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let frames = (0..2).map(|k| {
        let (depth, labels) = wall(40);
        Ok(Frame {
            id: FrameId::parse(&format!("bag/cam_00/{k}"))?,
            pose: pose(0.2 * k as f32, 0.1),
            rays: Arc::new(Rays::Pinhole(camera())),
            depth,
            depth_kind: DepthKind::Planar,
            labels: Some(labels),
            predictions: None,
        })
    });
    sndt_host::output::ros::write::write_trajectory(&dir.join("wall"), frames)?;
    Ok(())
}
