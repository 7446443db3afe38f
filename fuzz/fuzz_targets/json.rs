//! The prepared layout's JSON records (`extrinsics/*.json`, `intrinsics/*.json`) and its
//! split-list lines (`scene/cam/NNNN`) on arbitrary bytes, read as the dataset reader
//! reads them (serde_json, then `to_pose` / `to_pinhole`).
//!
//! A pose the reader accepts must pass the core's pose check and survive the writer's
//! inverse; a pinhole it accepts must be one the core renders with; a frame id must read
//! back from its own text.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_core::{validate_pose, Config, Isometry3, Map};
use sndt_host::dataset::prepared::{Extrinsics, Intrinsics};
use sndt_host::dataset::FrameId;

fuzz_target!(|data: &[u8]| {
    if let Ok(e) = serde_json::from_slice::<Extrinsics>(data) {
        extrinsics(&e);
    }
    if let Ok(i) = serde_json::from_slice::<Intrinsics>(data) {
        intrinsics(&i);
    }
    if let Ok(text) = std::str::from_utf8(data) {
        for line in text.lines() {
            if let Ok(id) = FrameId::parse(line) {
                let again = FrameId::parse(&id.to_string());
                assert_eq!(
                    again.ok().as_ref(),
                    Some(&id),
                    "{line:?} does not read back"
                );
            }
        }
    }
});

fn extrinsics(e: &Extrinsics) {
    let Ok(pose) = e.to_pose() else {
        return;
    };
    assert_eq!(
        validate_pose(&pose),
        Ok(()),
        "{e:?} gives a pose the core refuses"
    );
    let back = Extrinsics::from_pose(&pose)
        .to_pose()
        .expect("the writer's record reads");
    let dt = (back.translation.vector - pose.translation.vector).norm();
    let dq = back.rotation.angle_to(&pose.rotation);
    assert!(dt == 0.0 && dq < 1e-3, "{e:?}: written back as {back:?}");
}

fn intrinsics(i: &Intrinsics) {
    let Ok(cam) = i.to_pinhole() else {
        return;
    };
    let Some(n) = (cam.width as usize).checked_mul(cam.height as usize) else {
        return;
    };
    if n > 4096 {
        return;
    }
    // Rendering checks the camera as integration does; an empty map draws nothing.
    let map: Map<1, 1, 1> = Map::new(Config::DEFAULT);
    let (mut labels, mut dist) = (vec![0u8; n], vec![0f32; n]);
    let r = map.render(&Isometry3::identity(), &cam, &mut labels, &mut dist);
    assert_eq!(r, Ok(()), "{i:?} gives a pinhole the core refuses");
}
