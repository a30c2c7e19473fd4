//! `beltune serve`: the interactive tuning page, see [`crate::serve`].

use crate::serve::{self, AppState};
use anyhow::Context;
use std::io::Write;
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `beltune serve`.
#[derive(clap::Args)]
pub struct Args {
    /// Commissioning folder: the model is read from DIR/commissioning.json; each Save
    /// writes a new folder DIR/tuned-<UTC time>/ (controller.toml, report, data), the
    /// commissioning's own files stay as they are. Without it: the built-in egc70 axis,
    /// saving tuned-*/ folders into the current directory.
    #[arg(long, value_name = "DIR")]
    pub commissioning: Option<PathBuf>,
    /// Address to listen on. Anything but loopback needs --allow-remote.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: IpAddr,
    /// TCP port (0 = any free port).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Allow a non-loopback --bind: the page has no authentication and can save
    /// controllers (tuned-*/ folders), so everyone who can reach the port can do that.
    #[arg(long)]
    pub allow_remote: bool,
}

/// Refuse a non-loopback address unless `allow_remote`; return the warning to print.
pub fn check_bind(bind: IpAddr, allow_remote: bool) -> anyhow::Result<Option<String>> {
    if bind.is_loopback() {
        return Ok(None);
    }
    if !allow_remote {
        return Err(super::commission::preflight::bad(format!(
            "refusing to bind to non-loopback address {bind}: the tuning page has no \
             authentication; pass --allow-remote to do it anyway"
        )));
    }
    Ok(Some(format!(
        "warning: serving on {bind}, reachable from other machines; anyone who can reach \
         it can change the design and save controllers"
    )))
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(warning) = check_bind(args.bind, args.allow_remote)? {
        eprintln!("{warning}");
    }
    let (tuner, save_dir) = match &args.commissioning {
        Some(dir) => {
            let model = serve::library::load_commissioning(dir)?;
            (serve::library::LibraryTuner::new(model)?, dir.clone())
        }
        None => (
            serve::library::LibraryTuner::builtin()?,
            std::env::current_dir().context("current directory")?,
        ),
    };
    // Temporaries of a save that a killed server left behind.
    beltune::io::clean_stale_temporaries(&save_dir);
    let state = AppState {
        tuner: Arc::new(tuner),
        save_dir,
        loopback_only: args.bind.is_loopback(),
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async move {
        let addr = SocketAddr::new(args.bind, args.port);
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .with_context(|| format!("binding {addr}"))?;
        let local = listener.local_addr().context("local address")?;
        // A closed stdout must not end the server: ignore the error.
        let _ = writeln!(
            std::io::stdout(),
            "beltune tuning page: http://{local}/  (Ctrl-C to stop)"
        );
        tokio::select! {
            r = serve::serve(listener, state) => r.context("serving")?,
            _ = tokio::signal::ctrl_c() => {}
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_is_allowed_remote_needs_the_flag() {
        assert_eq!(
            check_bind("127.0.0.1".parse().unwrap(), false).unwrap(),
            None
        );
        assert_eq!(check_bind("::1".parse().unwrap(), false).unwrap(), None);
        let e = check_bind("0.0.0.0".parse().unwrap(), false).unwrap_err();
        assert!(e.to_string().contains("--allow-remote"), "{e}");
        assert_eq!(
            crate::exit::status_of(&e),
            crate::exit::ExitStatus::BadInput
        );
        let w = check_bind("0.0.0.0".parse().unwrap(), true)
            .unwrap()
            .unwrap();
        assert!(w.starts_with("warning:"), "{w}");
    }
}
