//! `beltune export`: the controller of a `controller.toml` as firmware source,
//! a Rust module of `beltune_rt` constants or a C header for `beltune_rt.h`
//! (crate beltune-rt-ffi), with the same values to the last digit.

use beltune::record::controller::ControllerFile;
use beltune::record::export::{export_as, Lang, Precision};
use std::path::PathBuf;

/// Target language.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum LangArg {
    /// A Rust module (`pub const CASCADE: beltune_rt::control::CascadeConfig<f64>`).
    Rust,
    /// A C header (`static const BtCascadeConfig BELTUNE_CASCADE`).
    C,
}

/// Float type of the export.
#[derive(Clone, Copy, Debug, Default, clap::ValueEnum)]
pub enum PrecisionArg {
    /// Double precision (`f64`), the values exactly as in the file.
    #[default]
    F64,
    /// Single precision (`f32`, C `float`): for MCUs with a single-precision FPU.
    F32,
}

/// Arguments of `beltune export`.
#[derive(clap::Args)]
pub struct Args {
    /// The controller file written by `beltune commission` (or `beltune serve`).
    #[arg(long)]
    pub controller: PathBuf,
    /// Target language.
    #[arg(long, value_enum)]
    pub lang: LangArg,
    /// Float type of the constants and structs (f32: `CascadeConfig<f32>` in
    /// Rust, `BtCascadeConfigF32` and `float` constants in C).
    #[arg(long, value_enum, default_value = "f64")]
    pub precision: PrecisionArg,
    /// Write here instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(out) = &args.out {
        super::util::check_not_an_input("--out", out, &[&args.controller])?;
    }
    let file = ControllerFile::load(&args.controller)?;
    let lang = match args.lang {
        LangArg::Rust => Lang::Rust,
        LangArg::C => Lang::C,
    };
    let precision = match args.precision {
        PrecisionArg::F64 => Precision::F64,
        PrecisionArg::F32 => Precision::F32,
    };
    let text = export_as(&file, lang, precision)?;
    match &args.out {
        Some(path) => {
            super::util::write_atomic(path, text.as_bytes())?;
            println!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    Ok(())
}
