//! `sndt experiment`'s command line: `--cell` is the cell sizes' spelling (as in `map` and
//! `compare`); the old `--cells` still works, hidden, with a deprecation warning, and
//! cannot be given beside `--cell`; `--help` ends with an example.

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
fn the_old_cells_option_still_works_with_a_warning() {
    let out = std::env::temp_dir().join(format!("sndt-experiment-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = experiment(&[
        "synthetic:1:2",
        "--methods",
        "sndt",
        "--labels",
        "gt",
        "--cells",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (text(&run.stdout), text(&run.stderr));
    assert!(run.status.success(), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("warning: --cells is deprecated and will be removed; use --cell"),
        "{stderr}"
    );
    assert!(
        stdout.contains("resumed 0 of 1 runs, computed 1"),
        "{stdout}"
    );
    // The value given to --cells is the one run.
    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    assert!(
        table.starts_with("| labels | method | mIoU 10cm |"),
        "{table}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn cells_and_cell_together_are_refused() {
    let run = experiment(&["synthetic:1:2", "--cells", "0.1", "--cell", "0.2"]);
    assert_eq!(run.status.code(), Some(2));
    let stderr = text(&run.stderr);
    assert!(
        stderr.contains("--cells") && stderr.contains("--cell"),
        "{stderr}"
    );
}

#[test]
fn help_shows_cell_not_cells_and_ends_with_an_example() {
    let run = experiment(&["--help"]);
    assert!(run.status.success());
    let help = text(&run.stdout);
    assert!(help.contains("--cell <CELL>"), "{help}");
    assert!(!help.contains("--cells"), "{help}");
    assert!(
        help.trim_end().ends_with(
            "Example:\n  sndt experiment synthetic --every 2 --cell 0.05,0.1 --out out/experiment"
        ),
        "{help}"
    );
}
