//! The C types mirror the core's: the same fields in the same order, the same default
//! values, and docs (in `src/types.rs` and the generated `include/sndt.h`) that state the
//! core's defaults. These types are written by hand for `repr(C)`, so without these tests a
//! changed default or a new field in the core would leave the header saying something else.

extern crate std;
use super::*;
use sndt_core::{Config, FrameReport, Pinhole};
use std::string::{String, ToString};
use std::vec::Vec;
use std::{format, vec};

/// `(field, value)` pairs of a struct's `Debug` text (`Name { a: 1, b: 2.5 }`); values
/// are flat here (numbers and enum variants).
fn debug_fields(debug: &str) -> Vec<(String, String)> {
    let inner = debug
        .split_once('{')
        .and_then(|(_, rest)| rest.rsplit_once('}'))
        .map_or("", |(inner, _)| inner);
    inner
        .split(',')
        .filter_map(|pair| pair.split_once(':'))
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .collect()
}

/// `(field, doc text)` of every field of the struct that starts at the line containing
/// `opening`, from Rust (`/// doc` then `pub name: T,`) or C (`/** * doc */` then
/// `T name;`) source.
fn field_docs(source: &str, opening: &str) -> Vec<(String, String)> {
    let mut fields = Vec::new();
    let mut doc = String::new();
    let mut lines = source.lines().skip_while(|l| !l.contains(opening)).skip(1);
    for line in lines.by_ref() {
        let t = line.trim();
        if t.starts_with('}') {
            break;
        }
        let text = t
            .trim_start_matches("///")
            .trim_start_matches("/**")
            .trim_end_matches("*/")
            .trim_start_matches('*')
            .trim();
        let is_comment = t.starts_with("///") || t.starts_with("/**") || t.starts_with('*');
        if is_comment {
            doc.push_str(text);
            doc.push(' ');
            continue;
        }
        let declaration = t.trim_end_matches([',', ';']);
        let name = match declaration.split_once(':') {
            Some((lhs, _)) => lhs.trim_start_matches("pub").trim(),
            None => declaration.rsplit(' ').next().unwrap_or(""),
        };
        if !name.is_empty() {
            fields.push((name.to_string(), core::mem::take(&mut doc)));
        }
    }
    fields
}

/// The default a field's doc states: the word after `Default`, or for a field documented
/// as a list of codes (`0 NDT-OM (default), 1 constant miss`) the code marked `(default)`.
fn documented_default(doc: &str) -> Option<String> {
    let words: Vec<&str> = doc.split_whitespace().collect();
    if let Some(i) = words.iter().position(|w| *w == "Default") {
        let word = words.get(i + 1)?.trim_end_matches(['.', ',']);
        return Some(word.to_string());
    }
    let marked = words.iter().position(|w| w.starts_with("(default)"))?;
    words[..marked]
        .iter()
        .rev()
        .find(|w| w.parse::<u32>().is_ok())
        .map(|w| w.to_string())
}

/// The core's default of each `Config` field, as the C side spells it: numbers, and the
/// miss model as its `u8` code.
fn core_defaults() -> Vec<(String, String)> {
    debug_fields(&format!("{:?}", Config::DEFAULT))
        .into_iter()
        .map(|(name, value)| match name.as_str() {
            "miss_model" => (name, (Config::DEFAULT.miss_model as u8).to_string()),
            _ => (name, value),
        })
        .collect()
}

/// Equal as the `f32` (or integer) the field holds: `0.10` and `0.1` agree.
fn same_number(doc: &str, value: &str) -> bool {
    match (doc.parse::<f64>(), value.parse::<f64>()) {
        (Ok(a), Ok(b)) => a as f32 == b as f32,
        _ => false,
    }
}

fn names(fields: &[(String, String)]) -> Vec<&str> {
    fields.iter().map(|(n, _)| n.as_str()).collect()
}

#[test]
fn config_has_the_core_fields_and_default_values() {
    let core = core_defaults();
    let c = debug_fields(&format!("{:?}", sndt_config::DEFAULT));
    assert_eq!(
        names(&c),
        names(&core),
        "sndt_config's fields are not Config's"
    );
    assert_eq!(c, core, "sndt_config::DEFAULT is not Config::DEFAULT");
    assert_eq!(sndt_config_default(), sndt_config::DEFAULT);
}

#[test]
fn config_docs_state_the_core_defaults() {
    let core = core_defaults();
    let sources = [
        (
            "src/types.rs",
            include_str!("types.rs"),
            "pub struct sndt_config {",
        ),
        (
            "include/sndt.h",
            include_str!("../include/sndt.h"),
            "typedef struct sndt_config {",
        ),
    ];
    for (file, text, opening) in sources {
        let docs = field_docs(text, opening);
        assert_eq!(names(&docs), names(&core), "{file}: sndt_config's fields");
        for ((name, doc), (_, value)) in docs.iter().zip(&core) {
            let stated = documented_default(doc);
            assert!(
                stated.as_deref().is_some_and(|s| same_number(s, value)),
                "{file}: sndt_config.{name} documents the default {stated:?}, the core's is {value}"
            );
        }
    }
}

#[test]
fn the_default_scanner_reads_both_doc_styles() {
    let rust = "pub struct s {\n    /// Radius. Default 2.5.\n    pub r: f32,\n    /// 0 a (default), 1 b.\n    pub m: u8,\n}\n";
    let c = "typedef struct s {\n  /**\n   * Radius. Default 2.0.\n   */\n  float r;\n} s;\n";
    let r = field_docs(rust, "pub struct s {");
    assert_eq!(names(&r), ["r", "m"]);
    assert_eq!(documented_default(&r[0].1).as_deref(), Some("2.5"));
    assert_eq!(documented_default(&r[1].1).as_deref(), Some("0"));
    let h = field_docs(c, "typedef struct s {");
    assert_eq!(names(&h), ["r"]);
    assert!(!same_number(&documented_default(&h[0].1).unwrap(), "2.5"));
    assert!(same_number("0.10", "0.1") && !same_number("x", "1"));
}

#[test]
fn frame_report_mirrors_the_core_field_by_field() {
    // Distinct values, so a field converted from the wrong core field shows.
    let r = FrameReport {
        points_used: 1,
        truncated: 2,
        rejected_depth: 3,
        rejected_label: 4,
        rejected_out_of_range: 5,
        dropped_points: 6,
        dropped_misses: 7,
        end_voxels: 8,
        rays: 9,
        voxels_created: 10,
        blocks_created: 11,
        voxels_evicted: 12,
        blocks_evicted: 13,
        records_spilled: 14,
        records_dropped: 15,
    };
    let core = debug_fields(&format!("{r:?}"));
    let c = debug_fields(&format!("{:?}", sndt_frame_report::from(r)));
    assert_eq!(c, core);
    let values: Vec<&str> = core.iter().map(|(_, v)| v.as_str()).collect();
    let expected: Vec<String> = (1..=15).map(|i: u32| i.to_string()).collect();
    assert_eq!(
        values, expected,
        "a FrameReport field is missing from this test"
    );
}

#[test]
fn pinhole_mirrors_the_core_field_by_field() {
    let c = sndt_pinhole {
        fx: 1.5,
        fy: 2.5,
        cx: 3.5,
        cy: 4.5,
        width: 6,
        height: 7,
    };
    let core: Pinhole = c.to_core();
    assert_eq!(
        debug_fields(&format!("{c:?}")),
        debug_fields(&format!("{core:?}"))
    );
    assert_eq!(
        debug_fields(&format!("{core:?}")).len(),
        6,
        "{:?}",
        vec![core]
    );
}
