//! `sndt experiment --resume` continues an interrupted experiment: a small experiment (two
//! synthetic trajectories of 3 frames, one cell size, one kernel: 8 runs) runs once
//! uninterrupted; a second one is stopped after 3 runs are stored
//! (`SNDT_EXPERIMENT_STOP_AFTER`, a test hook that exits with code 86), is refused a
//! resume under other options, then resumed: it must take the 3 stored runs without
//! touching them, compute the other 5 and write the same tables as the uninterrupted run
//! (update times aside, which differ between any two runs). A stored run then truncated is
//! reported and recomputed on the next resume.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::SystemTime;

const EXPERIMENT: [&str; 6] = [
    "experiment",
    "synthetic:2:3",
    "--cell",
    "0.2",
    "--kernels",
    "0.4",
];

/// The hook's exit code (`sndt_host::eval::experiment::store::STOP_EXIT_CODE`).
const STOPPED: i32 = 86;

/// Runs the small experiment into `out` with `extra` arguments and environment.
fn sndt(out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sndt"))
        .args(EXPERIMENT)
        .arg("--out")
        .arg(out)
        .args(extra)
        .envs(env.iter().cloned())
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Asserts that `out` succeeded; returns its stdout.
fn succeeded(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// The stored runs in `dir/runs` (not the manifest, not the input scores): file name to
/// content and modification time.
fn stored_runs(dir: &Path) -> BTreeMap<String, (Vec<u8>, SystemTime)> {
    std::fs::read_dir(dir.join("runs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            name.ends_with(".json") && name != "manifest.json" && !name.ends_with("__inputs.json")
        })
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let modified = std::fs::metadata(&p).unwrap().modified().unwrap();
            (name, (std::fs::read(&p).unwrap(), modified))
        })
        .collect()
}

/// `results.json` without its update times.
fn results_without_times(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("results.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for run in v["runs"].as_array_mut().unwrap() {
        let run = run.as_object_mut().unwrap();
        assert!(run.remove("mean_update_ms").is_some());
        for t in run["trajectories"].as_array_mut().unwrap() {
            assert!(t.as_object_mut().unwrap().remove("update_s").is_some());
        }
    }
    v
}

/// The first `n` columns of a CSV file.
fn csv_columns(path: &Path, n: usize) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').take(n).collect::<Vec<_>>().join(","))
        .collect()
}

/// The tables of `b` equal those of `a` in everything but update times.
fn assert_same_tables(a: &Path, b: &Path) {
    for name in [
        "table1.md",
        "table1.csv",
        "holes.md",
        "iou_gt.svg",
        "iou_pred.svg",
    ] {
        assert!(
            std::fs::read(a.join(name)).unwrap() == std::fs::read(b.join(name)).unwrap(),
            "{name} differs"
        );
    }
    // Table II is update rates: its rows must match, its figures are times.
    let t2 = |d: &Path| csv_columns(&d.join("table2.csv"), 3);
    assert_eq!(t2(a), t2(b));
    assert_eq!(t2(a).len(), 1 + 3);
    assert_eq!(results_without_times(a), results_without_times(b));
}

/// A scratch directory, emptied.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sndt-resume-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The update time a stored run file records, and its key in `results.json`.
fn stored_time(bytes: &[u8]) -> (f64, String, String) {
    let v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    let seconds: f64 = v["update_s"].as_str().unwrap().parse().unwrap();
    let cell = v["cell_mm"].as_u64().unwrap() as f64 / 1000.0;
    let labels = v["labels"].as_str().unwrap().to_string();
    let method = v["results"][0]["method"].as_str().unwrap();
    let trajectory = v["trajectory"].as_str().unwrap();
    (
        seconds,
        format!("{labels} {method} {cell}"),
        trajectory.to_string(),
    )
}

/// The update time `results.json` in `dir` gives run `key` on `trajectory`.
fn reported_time(dir: &Path, key: &str, trajectory: &str) -> f64 {
    let text = std::fs::read_to_string(dir.join("results.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let run = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| {
            let k = format!(
                "{} {} {}",
                r["labels"].as_str().unwrap(),
                r["method"].as_str().unwrap(),
                r["cell_m"].as_f64().unwrap()
            );
            k == key
        })
        .unwrap();
    let t = run["trajectories"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == trajectory)
        .unwrap();
    t["update_s"].as_f64().unwrap()
}

#[test]
fn an_interrupted_experiment_resumes_to_the_same_tables() {
    // Uninterrupted, in a directory holding an older experiment's runs under other
    // options: without --resume they are removed, not refused and not used.
    let full = scratch("full");
    std::fs::create_dir_all(full.join("runs")).unwrap();
    std::fs::write(full.join("runs/manifest.json"), "{\"format\": \"old\"}").unwrap();
    std::fs::write(full.join("runs/old__gt__sndt__cell100mm.json"), "{}").unwrap();
    let stdout = succeeded(&sndt(&full, &[], &[]));
    assert!(
        stdout.contains("resumed 0 of 8 runs, computed 8"),
        "{stdout}"
    );
    assert!(!full.join("runs/old__gt__sndt__cell100mm.json").exists());
    assert_eq!(stored_runs(&full).len(), 8);

    // Interrupted after 3 runs: exactly those are on disk, no tables yet.
    let out = scratch("interrupted");
    let stopped = sndt(&out, &[], &[("SNDT_EXPERIMENT_STOP_AFTER", "3")]);
    assert_eq!(
        stopped.status.code(),
        Some(STOPPED),
        "{}",
        text(&stopped.stderr)
    );
    let first = stored_runs(&out);
    assert_eq!(first.len(), 3, "{:?}", first.keys());
    assert!(!out.join("table1.md").exists());

    // Other options: refused, naming the manifest and each option that differs.
    assert_refused(&out);
    assert_eq!(
        stored_runs(&out),
        first,
        "a refused resume changed the stored runs"
    );

    // Resumed: the 3 stored runs are taken as they are (not rewritten, so not
    // recomputed), the other 5 computed; the tables are the uninterrupted run's.
    let stdout = succeeded(&sndt(&out, &["--resume"], &[]));
    assert!(
        stdout.contains("resumed 3 of 8 runs, computed 5"),
        "{stdout}"
    );
    let all = stored_runs(&out);
    assert_eq!(all.len(), 8);
    for (name, stored) in &first {
        assert!(&all[name] == stored, "{name} was rewritten");
        // Their update times are the ones measured before the interruption.
        let (seconds, key, trajectory) = stored_time(&stored.0);
        let reported = reported_time(&out, &key, &trajectory);
        assert!(
            (reported - seconds).abs() <= 1e-12 * seconds,
            "{name}: {reported} s reported, {seconds} s stored"
        );
    }
    assert_same_tables(&full, &out);

    // A stored run cut short: reported by name and recomputed, the rest resumed.
    let (name, (bytes, _)) = first.iter().next().unwrap();
    resume_with_a_truncated_run(&full, &out, name, bytes);

    let _ = std::fs::remove_dir_all(&full);
    let _ = std::fs::remove_dir_all(&out);
}

/// Resuming `out` under options other than its stored runs' is refused, naming the
/// manifest and the option that differs.
fn assert_refused(out: &Path) {
    for (extra, differs) in [
        // clap appends a repeated `--cell` to the first.
        (
            &["--resume", "--cell", "0.25"][..],
            "--cell: stored 0.2, now 0.2,0.25",
        ),
        (
            &["--resume", "--every", "2"][..],
            "--every: stored 1, now 2",
        ),
        (
            &["--resume", "--labels", "gt"][..],
            "--labels: stored gt,pred, now gt",
        ),
    ] {
        let refused = sndt(out, extra, &[]);
        let err = text(&refused.stderr);
        assert!(!refused.status.success(), "{extra:?} was not refused");
        assert!(err.contains("cannot resume"), "{err}");
        let manifest = out.join("runs/manifest.json");
        assert!(err.contains(&*manifest.to_string_lossy()), "{err}");
        assert!(err.contains(differs), "{extra:?}: {err}");
    }
}

/// Truncates the stored run `name` (content `bytes`) of `out` and resumes: the file is
/// reported by name and recomputed, the other 7 runs resumed, and the tables are still
/// those of `full`.
fn resume_with_a_truncated_run(full: &Path, out: &Path, name: &str, bytes: &[u8]) {
    let path = out.join("runs").join(name);
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let again = sndt(out, &["--resume"], &[]);
    let stdout = succeeded(&again);
    let err = text(&again.stderr);
    assert!(
        err.contains(&format!("warning: {}", path.display())) && err.contains("recomputing"),
        "{err}"
    );
    assert!(
        stdout.contains("resumed 7 of 8 runs, computed 1"),
        "{stdout}"
    );
    serde_json::from_slice::<serde_json::Value>(&std::fs::read(&path).unwrap()).unwrap();
    assert_same_tables(full, out);
}
