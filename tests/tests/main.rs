//! sndt's integration tests, one module per file of this directory, in one test binary:
//! every file linked into its own binary would compile the map's generic code and link
//! `sndt-host` once per file. Run one file's tests with its module name as the
//! filter, e.g. `cargo test -p sndt-tests --test integration snapshot::`.

mod bad_input;
mod bki;
mod capacity;
mod crosscheck;
mod dda;
mod dispatch;
mod dynamics;
mod evaluate;
mod fuzz;
mod gaussian;
mod hypersim;
mod layout;
mod merge;
mod octomap;
mod permutation;
mod points_export;
mod prepared;
mod reference;
mod render;
mod ros;
mod scenes;
mod snapshot;
mod spill;
mod synth;
