//! The dynamics report on the dynamic synthetic room, small camera: S-NDT as published
//! against the see-through miss, measured the same way.

use sndt_core::Config;
use sndt_host::dataset::synthetic::{dynamic, DynamicOptions, SynthOptions, Synthetic};
use sndt_host::dataset::{Dataset, LabelSource};
use sndt_host::eval::dynamics::{run, DynamicsOptions, Mapper};
use sndt_tests::SMALL_CAMERA;

#[test]
fn see_through_miss_clears_what_moved_and_keeps_the_static_scene() {
    let split = Synthetic::new(SynthOptions {
        dynamic: Some(DynamicOptions::default()),
        frames: dynamic::DEFAULT_FRAMES,
        camera: SMALL_CAMERA,
        predictions: false,
        ..SynthOptions::default()
    })
    .unwrap();
    let mapper = |name: &str, see: f32| Mapper {
        name: name.into(),
        config: Config {
            see_through_miss: see,
            ..Config::DEFAULT
        },
    };
    let options = DynamicsOptions {
        mappers: vec![mapper("published", 0.0), mapper("see-through", -3.0)],
        labels: LabelSource::Gt,
        octomap: None,
        work: std::env::temp_dir(),
    };
    let report = run(&split, &options, &|| {}).unwrap();
    let [published, see] = &report.mappers[..] else {
        panic!("two maps, no OctoMap");
    };
    let table = report.table();
    for m in [published, see] {
        assert_eq!(m.events.len(), 5, "{table}");
        for (e, event) in m.events.iter().zip(&report.events) {
            assert_eq!(e.ghost.len(), dynamic::DEFAULT_FRAMES);
            // Before the first change the map holds all of what it will lose.
            if event.first == event.vacated {
                assert_eq!(
                    e.ghost[event.first as usize - 1],
                    1.0,
                    "{}: {table}",
                    e.name
                );
            }
            assert!(
                e.former > 0 && e.seen_through.is_some(),
                "{}: {table}",
                e.name
            );
        }
        // Static loss at most 1 % of the static surface.
        assert!(
            m.static_lost * 100 <= m.static_voxels,
            "{}: {table}",
            m.name
        );
        assert!(m.metrics.is_some());
    }
    let frames = |f: Option<u32>| f.unwrap_or(u32::MAX);
    for (p, s) in published.events.iter().zip(&see.events) {
        assert!(
            frames(s.frames_to_clear) <= frames(p.frames_to_clear),
            "{}: {table}",
            p.name
        );
    }
    // The fresh twins start at the first change and never see the night stand: as
    // published, the map keeps the stand's votes where the box now stands and never
    // relabels it within the walk, while its twin does. Events without a new object
    // have no relabel figure either way.
    for m in [published, see] {
        for (e, event) in m.events.iter().zip(&report.events) {
            let applies = event.new.is_some() && event.first == report.events[0].first;
            assert_eq!(
                e.fresh_frames_to_relabel.is_some(),
                applies,
                "{}: {table}",
                e.name
            );
        }
    }
    let box_event = &published.events[1];
    assert!(
        box_event.frames_to_relabel.is_none() && box_event.fresh_frames_to_relabel.is_some(),
        "{table}"
    );
    // The moved chair and the person: published NDT-OM misses reach their thin former
    // voxels only from the rare ray through them, and they stay all the walk; with the
    // see-through miss the pixels through their Gaussians' means see the floor and the
    // wall behind, and they clear in the two frames a clamped voxel needs, give or take
    // one (OctoMap takes 10 and 11, docs/DYNAMICS.md).
    for (event, name) in [(0, "chair"), (3, "person")] {
        let clear =
            |m: &sndt_host::eval::dynamics::MapperResult| frames(m.events[event].frames_to_clear);
        assert!(clear(see) <= 3 && clear(published) > 150, "{name}: {table}");
    }
}

/// The floor walk with people in the corridor: every person adds person pixels to the
/// ground truth of some frame while it crosses (against the frozen twin, whose rooms hold
/// their own standing figures; the renderer's labels, not the view test that chose its
/// start), never stands within 0.5 m of the camera, and is gone once vacated; the frozen
/// twin has no walking person at any frame; a walk too short for the people is refused
/// with the frames it needs.
#[test]
fn floor_walk_with_people_in_the_corridor() {
    use sndt_host::dataset::synthetic::scenes::class::PERSON;
    use sndt_host::dataset::synthetic::{floor, people};
    let walk = |frozen| {
        Synthetic::new(SynthOptions {
            dynamic: Some(DynamicOptions {
                floor_walk: Some(1),
                frozen,
                ..DynamicOptions::default()
            }),
            frames: floor::DEFAULT_FRAMES,
            camera: SMALL_CAMERA,
            predictions: false,
            ..SynthOptions::default()
        })
        .unwrap()
    };
    let (split, frozen) = (walk(false), walk(true));
    let scene = split.dynamic_scene().unwrap();
    let still = frozen.dynamic_scene().unwrap();
    assert_eq!(
        (scene.name, scene.events.len()),
        (people::NAME, people::PEOPLE)
    );
    let persons = |s: &Synthetic, f: u32| {
        let (frame, _) = s.render_frame(&s.frames()[f as usize]).unwrap();
        let labels = frame.labels.unwrap();
        labels.iter().filter(|&&l| l == PERSON).count()
    };
    for e in &scene.events {
        assert!(e.first < e.vacated && (e.vacated as usize) < scene.frames);
        let walker = |p: &&sndt_host::dataset::synthetic::geometry::Primitive| e.old.contains(*p);
        let mut shown = (e.first..e.vacated)
            .step_by(3)
            .filter(|&f| persons(&split, f) > persons(&frozen, f));
        assert!(shown.next().is_some(), "{}: never in view", e.name);
        for f in e.first..e.vacated {
            let eye = scene.pose(f).translation.vector;
            let now = scene.primitives_at(f);
            let near = now.iter().filter(walker).any(|p| {
                let b = p.shape.aabb();
                (0..2).all(|a| b.min[a] - 0.5 < eye[a] && eye[a] < b.max[a] + 0.5)
            });
            assert!(!near, "{}: within 0.5 m of the camera at frame {f}", e.name);
            assert_eq!(still.primitives_at(f).iter().filter(walker).count(), 0);
        }
        assert_eq!(
            scene.primitives_at(e.vacated).iter().filter(walker).count(),
            0
        );
    }
    for spec in ["synthetic:floor-people:1:300", "synthetic:floor-people:2"] {
        let d = sndt_host::dataset::open_spec(spec, &Default::default()).unwrap();
        assert!(d.describe().contains("3 people in the corridor"), "{spec}");
    }
    let short = sndt_host::dataset::open_spec("synthetic:floor-people:1:6", &Default::default());
    let err = format!("{:#}", short.err().unwrap());
    assert!(err.contains("give at least"), "{err}");
}
