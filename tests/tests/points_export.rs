//! `sndt points` (`sndt_host::output::points::write_points`): the file read back with an
//! independent parser holds the header, the frame count, each frame's sensor origin and
//! exactly the world points the core integrates (`pose * camera_point`, every measured
//! pixel, row-major).

use sndt_core::{Pinhole, Point3};
use sndt_host::dataset::{Dataset, Frame};
use sndt_host::output::points::write_points;

const CAM: Pinhole = Pinhole {
    fx: 55.4,
    fy: 55.4,
    cx: 32.0,
    cy: 24.0,
    width: 64,
    height: 48,
};

/// A little-endian cursor over the file.
struct Cursor<'a>(&'a [u8]);

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.0.len() >= n, "file ends early");
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        head
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }

    fn xyz(&mut self) -> [f32; 3] {
        [0; 3].map(|_| f32::from_le_bytes(self.take(4).try_into().unwrap()))
    }
}

/// The frame's expected world points, computed here from the camera points.
fn expected_points(frame: &Frame) -> Vec<[f32; 3]> {
    (0..frame.pixels())
        .filter_map(|i| frame.camera_point(i))
        .map(|p| {
            let w = frame.pose * Point3::from(p);
            [w.x, w.y, w.z]
        })
        .collect()
}

#[test]
fn exported_points_are_the_frames_world_points() {
    let split = sndt_tests::synthetic(1, 4, CAM, false);
    let ids = &split.frames()[..3];
    let out = std::env::temp_dir()
        .join(format!("sndt-points-{}", std::process::id()))
        .join("points.bin");
    let summary = write_points(&split, ids, &out).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();

    let mut r = Cursor(&bytes);
    assert_eq!(r.take(8), b"SNDTPTS1");
    assert_eq!(r.u32(), 3);
    let mut total = 0;
    for id in ids {
        let frame = split.load(id).unwrap();
        let t = frame.pose.translation.vector;
        assert_eq!(r.xyz(), [t.x, t.y, t.z], "{id}: origin");
        let n = r.u32() as usize;
        let points: Vec<[f32; 3]> = (0..n).map(|_| r.xyz()).collect();
        let expected = expected_points(&frame);
        assert!(
            expected.len() > CAM.width as usize * CAM.height as usize / 2,
            "{id}: most pixels measure"
        );
        // Bit for bit: the same f32 arithmetic, in the same pixel order.
        assert_eq!(points, expected, "{id}: points");
        total += n;
    }
    assert!(r.0.is_empty(), "trailing bytes");
    assert_eq!((summary.frames, summary.points), (3, total));
}
