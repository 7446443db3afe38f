//! `sndt`: the host command line (see [`sndt_host::cli`]).

fn main() -> anyhow::Result<()> {
    sndt_host::cli::main()
}
