//! `p3dp send FILE… --to URL [--print]`: uploads built files to the
//! printer's host (Moonraker, OctoPrint or PrusaLink; see
//! [`crate::output::host::send`]). The API key comes from the environment
//! (`P3DP_API_KEY`), never the command line, and is never printed.

use std::path::PathBuf;
use std::time::Duration;

use crate::base::error::{Error, Result};
use crate::output::host::send::{Host, Target};

/// The environment variable that holds the host's API key.
pub(crate) const KEY_VAR: &str = "P3DP_API_KEY";

/// What `send` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// The host's base URL.
    pub to: String,
    /// Start printing the (last) file once it is there.
    pub print: bool,
    /// The host, when not found by asking it.
    pub host: Option<String>,
    /// Seconds a request may take.
    pub timeout: u64,
}

/// Sends every file; one error per file that did not arrive (the others
/// are still sent). A file's line on standard output says where it went.
pub(crate) fn run(a: &Options) -> Result<Vec<Error>> {
    if a.files.is_empty() {
        return Err(Error::input(
            "",
            "no file given; expected one or more FILEs to send",
        ));
    }
    if !(a.to.starts_with("http://") || a.to.starts_with("https://")) {
        return Err(Error::input(
            "--to",
            format!("`{}` is not a URL; expected http://HOST[:PORT]", a.to),
        ));
    }
    if a.to.starts_with("https://") {
        return Err(Error::input(
            "--to",
            "p3dp speaks plain HTTP only (printer hosts on a local network); expected http://HOST[:PORT]",
        ));
    }
    let key = std::env::var(KEY_VAR).ok().filter(|k| !k.trim().is_empty());
    let target = Target {
        url: a.to.clone(),
        key: key.map(|k| k.trim().to_string()),
        timeout: Duration::from_secs(a.timeout.max(1)),
    };
    let host = match &a.host {
        Some(h) => Host::of_name(h).ok_or_else(|| {
            Error::input(
                "--host",
                format!("unknown host `{h}`; expected moonraker, octoprint or prusalink"),
            )
        })?,
        None => target.detect()?,
    };
    let mut errors = Vec::new();
    for (k, f) in a.files.iter().enumerate() {
        // only the last file prints: a host prints one at a time
        let print = a.print && k + 1 == a.files.len();
        if let Err(e) = send_one(&target, host, f, print) {
            errors.push(e);
        }
    }
    Ok(errors)
}

/// Reads one file and uploads it with a progress bar on a terminal.
fn send_one(target: &Target, host: Host, file: &std::path::Path, print: bool) -> Result<()> {
    let shown = file.display().to_string();
    let bytes = std::fs::read(file)
        .map_err(|e| Error::io_from(shown.clone(), format!("cannot read: {e}"), &e))?;
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| Error::input(shown.clone(), "not a file name"))?;
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(bytes.len() as u64),
        indicatif::ProgressDrawTarget::stderr_with_hz(4),
    );
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:30} {bytes}/{total_bytes} {msg}")
    {
        bar.set_style(style);
    }
    bar.set_message(name.clone());
    let sent = target.upload(host, &name, &bytes, print, &mut |n| bar.set_position(n));
    bar.finish_and_clear();
    let sent = sent.map_err(|e| Error {
        file: Some(shown.clone()),
        place: Some(format!("sending to {} at {}", host.name(), target.url)),
        ..e
    })?;
    crate::sayln!(
        "{shown}: sent to {} at {} as {} ({} bytes){}",
        host.name(),
        target.url,
        sent.path,
        bytes.len(),
        if sent.printing { ", printing" } else { "" }
    );
    Ok(())
}
