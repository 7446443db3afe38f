//! `sndt experiment`'s command line: `--cell` is the cell sizes' spelling (as in `map` and
//! `compare`; `--cells` is refused), `--labels` is a comma-separated list of the label values
//! `map` takes (of which the experiment runs `gt` and `pred`), and `--help` ends with an
//! example.

use std::process::{Command, Output};

/// Runs `sndt experiment args`.
fn experiment(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sndt"))
        .arg("experiment")
        .args(args)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn labels_is_a_list_of_label_values_each_run() {
    let out = std::env::temp_dir().join(format!("sndt-experiment-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = experiment(&[
        "synthetic:1:2",
        "--methods",
        "sndt",
        "--labels",
        "pred,gt",
        "--cell",
        "0.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (text(&run.stdout), text(&run.stderr));
    assert!(run.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("resumed 0 of 2 runs, computed 2"),
        "{stdout}"
    );
    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    assert!(
        table.contains("| GT segmentation |") && table.contains("| Predicted segmentation |"),
        "{table}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn other_labels_the_old_both_and_the_old_cells_are_refused() {
    for bad in ["both", "pred-topk", "none", "gt,both"] {
        let run = experiment(&["synthetic:1:2", "--labels", bad]);
        assert_eq!(run.status.code(), Some(2), "--labels {bad}");
        let stderr = text(&run.stderr);
        assert!(
            stderr.contains("invalid value") && stderr.contains("[possible values: gt, pred]"),
            "--labels {bad}: {stderr}"
        );
    }
    let run = experiment(&["synthetic:1:2", "--labels", "gt,gt"]);
    assert_eq!(run.status.code(), Some(1));
    let stderr = text(&run.stderr);
    assert!(stderr.contains("--labels: gt given twice"), "{stderr}");
    let run = experiment(&["synthetic:1:2", "--cells", "0.1"]);
    assert_eq!(run.status.code(), Some(2));
    let stderr = text(&run.stderr);
    assert!(stderr.contains("unexpected argument '--cells'"), "{stderr}");
}

#[test]
fn help_shows_cell_and_the_labels_list_and_ends_with_an_example() {
    let run = experiment(&["--help"]);
    assert!(run.status.success());
    let help = text(&run.stdout);
    assert!(help.contains("--cell <CELL>"), "{help}");
    assert!(!help.contains("--cells"), "{help}");
    assert!(
        help.contains("[default: gt,pred]") && help.contains("[possible values: gt, pred]"),
        "{help}"
    );
    assert!(
        help.trim_end().ends_with(
            "  sndt experiment data/synth --labels gt --methods sndt --out out/experiment-gt"
        ),
        "{help}"
    );
}
