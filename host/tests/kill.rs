//! A map file survives its writer being killed: `sndt map --save-maps` runs once to
//! completion; then it runs again with the same output, made to pause halfway through
//! writing each file (`SNDT_WRITE_PAUSE_MS`, a test hook), and is killed (SIGKILL) while
//! the map file is half written. The map file must still be the complete first map, and
//! load.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

fn sndt_map(out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sndt"));
    c.args([
        "map",
        "synthetic:1:3",
        "--cell",
        "0.2",
        "--save-maps",
        "--out",
    ])
    .arg(out)
    .stdout(std::process::Stdio::null())
    .stderr(std::process::Stdio::null());
    c
}

/// The map is being written: its temporary file exists in `dir`, or (were it written in
/// place) the map file no longer has its complete length `full`.
fn half_written(dir: &Path, full: usize) -> bool {
    let tmp = std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.filter_map(Result::ok).any(|e| {
            let name = e.file_name();
            name.to_string_lossy()
                .starts_with(".synth_00_living_cam_00.sndt.tmp")
        })
    });
    let in_place = std::fs::metadata(dir.join("synth_00_living_cam_00.sndt"))
        .is_ok_and(|m| m.len() as usize != full);
    tmp || in_place
}

#[test]
fn a_map_killed_while_saving_leaves_the_previous_map_intact() {
    let out = std::env::temp_dir().join(format!("sndt-kill-{}", std::process::id()));
    assert!(sndt_map(&out).status().unwrap().success());
    let maps = out.join("maps");
    let path = maps.join("synth_00_living_cam_00.sndt");
    let good = std::fs::read(&path).unwrap();
    sndt_host::eval::evaluate::load_snapshot(&path).unwrap();

    let mut child = sndt_map(&out)
        .env("SNDT_WRITE_PAUSE_MS", "60000")
        .spawn()
        .unwrap();
    // Wait (up to 10 minutes, however slow the machine) until the map is half written.
    let start = Instant::now();
    while !half_written(&maps, good.len()) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "sndt map ended before saving"
        );
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "the save never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL, mid-write
    child.wait().unwrap();
    assert!(
        std::fs::read(&path).unwrap() == good,
        "the map file changed"
    );
    sndt_host::eval::evaluate::load_snapshot(&path).unwrap();
    let _ = std::fs::remove_dir_all(&out);
}
