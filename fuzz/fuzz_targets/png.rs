//! The prepared layout's PNG readers (uint16 depth in millimetres, uint8 labels) on
//! arbitrary bytes. An accepted image has one sample per pixel; a small depth image is then
//! mapped as a frame (nominal-style pinhole of its size) with its labels when those decode
//! too.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_core::{DepthKind, Isometry3, Pinhole};
use sndt_fuzz::map_frame;
use sndt_host::dataset::prepared::{depth_png_from_bytes, labels_png_from_bytes};
use sndt_host::dataset::{Frame, FrameId, Rays};
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let labels = labels_png_from_bytes(data).ok();
    if let Some((w, h, l)) = &labels {
        assert_eq!(
            l.len() as u64,
            *w as u64 * *h as u64,
            "labels are not one per pixel"
        );
    }
    let Ok((w, h, mm)) = depth_png_from_bytes(data) else {
        return;
    };
    assert_eq!(
        mm.len() as u64,
        w as u64 * h as u64,
        "depth is not one sample per pixel"
    );
    if mm.len() > 4096 {
        return;
    }
    let camera = Pinhole {
        fx: w as f32,
        fy: w as f32,
        cx: w as f32 / 2.0,
        cy: h as f32 / 2.0,
        width: w,
        height: h,
    };
    let frame = Frame {
        id: FrameId::parse("fuzz/cam_00/0000").unwrap(),
        pose: Isometry3::identity(),
        rays: Arc::new(Rays::Pinhole(camera)),
        depth: mm.iter().map(|&v| v as f32 / 1000.0).collect(),
        depth_kind: DepthKind::Planar,
        labels: None,
        predictions: None,
    };
    if frame.validate().is_ok() {
        map_frame(&frame);
    }
});
