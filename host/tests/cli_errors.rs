//! Bad command lines: each exits non-zero with a message that names the option or the file
//! and says what is wrong.

use std::process::Command;

/// Runs `sndt args`; returns the exit code and stderr.
fn sndt(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sndt"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_option_values_are_refused_naming_the_option() {
    let ply = std::env::temp_dir().join(format!("sndt-cli-{}.ply", std::process::id()));
    let ply = ply.to_str().unwrap();
    for bad in ["NaN", "inf", "0", "-3"] {
        let option = format!("--ellipsoids={bad}");
        let (code, err) = sndt(&["export", "synthetic:1:2", "--ply", ply, &option]);
        assert_eq!(code, 2, "--ellipsoids {bad}: {err}");
        assert!(
            err.contains("--ellipsoids") && err.contains("must be a finite number > 0"),
            "{err}"
        );
    }
    assert!(!std::path::Path::new(ply).exists(), "nothing written");
    let cases: [(&[&str], &str, &str); 6] = [
        (&["map", "synthetic:1:2", "--cell", "0"], "--cell", "> 0"),
        (&["map", "synthetic:1:2", "--cell", "NaN"], "--cell", "> 0"),
        (&["map", "synthetic:1:2", "--stride", "0"], "--stride", "0"),
        (
            &["map", "synthetic:1:2", "--mcap", "m.mcap", "--every", "0"],
            "--every",
            "0",
        ),
        (
            &["experiment", "synthetic:1:2", "--cells", "0.1,-1"],
            "--cells",
            "> 0",
        ),
        (
            &["map", "synthetic:1:2", "--sync-tolerance=-1"],
            "--sync-tolerance",
            ">= 0",
        ),
    ];
    for (args, option, why) in cases {
        let (code, err) = sndt(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(option) && err.contains(why), "{args:?}: {err}");
    }
}

#[test]
fn missing_inputs_are_named() {
    let (code, err) = sndt(&["export", "nope.sndt", "--ply", "x.ply"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("nope.sndt: no such map snapshot file"),
        "{err}"
    );
    let (code, err) = sndt(&["map", "no-such-dataset"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("no-such-dataset: no such file or directory"),
        "{err}"
    );
    let (code, err) = sndt(&["info", "no-such.mcap"]);
    assert_ne!(code, 0);
    assert!(err.contains("no-such.mcap"), "{err}");
}
