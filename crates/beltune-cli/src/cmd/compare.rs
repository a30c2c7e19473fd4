//! `beltune compare A B`: a report comparing two commissionings:
//! both FRFs and fits, the loops and the moves overlaid, and the change of
//! every parameter in percent.

use beltune::report::compare::compare_report;
use beltune::report::render_html;
use std::path::PathBuf;

/// Arguments of `beltune compare`.
#[derive(clap::Args)]
pub struct Args {
    /// The first commissioning folder (the reference, "A").
    pub a: PathBuf,
    /// The second commissioning folder ("B"); changes are B against A.
    pub b: PathBuf,
    /// The report file to write (one self-contained HTML page).
    #[arg(long, default_value = "compare.html")]
    pub out: PathBuf,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    // the page must not replace a file of either folder it reads
    let mut inputs: Vec<PathBuf> = Vec::new();
    for dir in [&args.a, &args.b] {
        inputs.push(dir.join(beltune::record::COMMISSIONING_FILE));
        inputs.push(dir.join(beltune::record::CONTROLLER_FILE));
        inputs.push(dir.join(beltune::record::REPORT_FILE));
        for name in beltune::report::data_files::DATA_FILE_NAMES {
            inputs.push(dir.join(name));
        }
    }
    let inputs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    super::util::check_not_an_input("--out", &args.out, &inputs)?;
    super::util::check_writable_file("--out", &args.out)?;
    let report = compare_report(&args.a, &args.b)?;
    let html = render_html(&report)?;
    beltune::io::write_atomic(&args.out, html.as_bytes())?;
    println!("{}", report.summary);
    println!("wrote {}", args.out.display());
    Ok(())
}
