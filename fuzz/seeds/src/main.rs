//! Writes raw seed inputs for the fuzz targets into `<out>/<target>/`: snapshots the core
//! writes for a few small maps, and PNG, JSON, `.npy`, HDF5 and MCAP files the host's own
//! writers produce for small frames. `scripts/fuzz.sh --seeds` runs this and then merges
//! the result into `fuzz/corpus/` with libFuzzer's `-merge=1`, which keeps only inputs
//! that add coverage.
//!
//! Usage: `sndt-fuzz-seeds <out>` (the directory must not exist yet).

use anyhow::{bail, Context, Result};
use sndt_core::{
    Config, Depth, DepthImage, DepthKind, Isometry3, LabelImage, Map, MissModel, Pinhole,
    Translation3, UnitQuaternion, Vector3,
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

/// Integrates `frames` views of the wall and writes the snapshot.
fn map_snapshot<const C: usize>(config: Config, frames: usize) -> Result<Vec<u8>> {
    let mut map: Box<Map<256, 128, C>> = Box::new(Map::new(config));
    let (depth, labels) = wall(C as u8);
    for k in 0..frames {
        let image = DepthImage {
            camera: camera(),
            depth: Depth::Metres(&depth),
            kind: if k % 2 == 0 {
                DepthKind::Planar
            } else {
                DepthKind::Range
            },
            labels: LabelImage::Top1(&labels),
            stride: 1,
        };
        map.integrate_depth(&pose(0.1 * k as f32, 0.2 * k as f32), &image)
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
