//! Runtime CPU dispatch (`sndt-dispatch`): every level this CPU runs gives the same map
//! bytes and the same evicted records, for depth images with ground-truth, top-1 and
//! top-k labels, for point lists, and for a device-size map that evicts and spills. In a
//! build for baseline x86-64 the baseline level sums points by runs on SSE2 and the others
//! by voxel on AVX2 and AVX-512, so this compares different code on the same frames.

use sndt_core::{
    Config, Depth, DepthImage, FrameReport, LabelImage, Labels, Map, Record, RecordSink,
};
use sndt_dispatch::{integrate_at, integrate_depth_at, level, Level};
use sndt_host::dataset::frame::{Frame, Rays};
use sndt_host::dataset::{Dataset, LabelSource};
use sndt_host::mapping::{boxed_map, HostMap};

/// Every level up to the CPU's.
fn levels() -> Vec<Level> {
    [Level::Baseline, Level::Avx2, Level::Avx512]
        .into_iter()
        .filter(|&l| l <= level())
        .collect()
}

/// The walk's frames: one synthetic scene at a quarter of Hypersim's size, with the
/// simulated network's predictions.
fn frames() -> Vec<Frame> {
    let split = sndt_tests::synthetic(1, 8, sndt_tests::camera(256, 192), true);
    let ids = split.frames().to_vec();
    ids.iter().map(|id| split.load(id).unwrap()).collect()
}

/// Integrates `frame` as a depth image with labels from `source`, at `level`.
fn depth_frame<const V: usize, const B: usize, const C: usize>(
    level: Level,
    map: &mut Map<V, B, C>,
    frame: &Frame,
    source: LabelSource,
    sink: Option<&mut dyn RecordSink>,
) -> FrameReport {
    let Rays::Pinhole(camera) = frame.rays.as_ref() else {
        panic!("a synthetic frame has a pinhole camera");
    };
    let predictions = frame.predictions.as_ref().unwrap();
    let (top1, topk): (Vec<u8>, Vec<Labels>) = match source {
        LabelSource::Pred => (predictions.top1(), Vec::new()),
        LabelSource::PredTopk => (
            Vec::new(),
            (0..frame.pixels()).map(|i| predictions.labels(i)).collect(),
        ),
        _ => (Vec::new(), Vec::new()),
    };
    let labels = match source {
        LabelSource::Gt => LabelImage::Top1(frame.labels.as_deref().unwrap()),
        LabelSource::Pred => LabelImage::Top1(&top1),
        LabelSource::PredTopk => LabelImage::TopK(&topk),
        LabelSource::None => LabelImage::None,
    };
    let image = DepthImage {
        camera: *camera,
        depth: Depth::Metres(&frame.depth),
        kind: frame.depth_kind,
        labels,
        stride: 1,
    };
    integrate_depth_at(level, map, &frame.pose, &image, sink).unwrap()
}

#[test]
fn every_level_gives_the_same_map_for_every_kind_of_labels() {
    let frames = frames();
    for cell in [0.05, 0.1] {
        for source in [LabelSource::Gt, LabelSource::PredTopk, LabelSource::None] {
            let maps: Vec<Vec<u8>> = levels()
                .into_iter()
                .map(|l| {
                    let mut map: Box<HostMap> = boxed_map(Config::with_cell_size(cell)).unwrap();
                    for f in &frames {
                        depth_frame(l, &mut *map, f, source, None);
                    }
                    sndt_tests::snapshot(&*map)
                })
                .collect();
            assert!(maps[0].len() > 10_000, "{cell} {source:?}");
            assert!(
                maps.iter().all(|m| *m == maps[0]),
                "{cell} {source:?}: levels differ"
            );
        }
        // Points given as a list (the per-pixel-ray path).
        let maps: Vec<Vec<u8>> = levels()
            .into_iter()
            .map(|l| {
                let mut map: Box<HostMap> = boxed_map(Config::with_cell_size(cell)).unwrap();
                for f in &frames {
                    let points = f.camera_points(LabelSource::Pred, 1);
                    integrate_at(l, &mut *map, &f.pose, &points, None).unwrap();
                }
                sndt_tests::snapshot(&*map)
            })
            .collect();
        assert!(
            maps.iter().all(|m| *m == maps[0]),
            "{cell}: point lists differ"
        );
    }
}

/// A map of the firmware's size evicts every frame at 5 cm: each level evicts the same
/// entries in the same order, and ends with the same map.
#[test]
fn every_level_evicts_and_spills_the_same() {
    let frames = frames();
    let runs: Vec<(Vec<Vec<u8>>, Vec<u8>)> = levels()
        .into_iter()
        .map(|l| {
            let mut device: Box<Map<4096, 512, 40>> =
                Box::new(Map::new(Config::with_cell_size(0.05)));
            let mut records: Vec<Vec<u8>> = Vec::new();
            for f in &frames {
                let mut sink = |r: Record<'_>| {
                    records.push(r.bytes.to_vec());
                    true
                };
                let report = depth_frame(l, &mut *device, f, LabelSource::Gt, Some(&mut sink));
                assert_eq!(report.records_dropped, 0);
            }
            (records, sndt_tests::snapshot(&*device))
        })
        .collect();
    assert!(runs[0].0.len() > 1000, "{} records", runs[0].0.len());
    assert!(
        runs.iter().all(|r| *r == runs[0]),
        "levels evict differently"
    );
}
