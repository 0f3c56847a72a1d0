//! `p3dp send FILE… --to URL [--print]`: uploads built files to the
//! printer's host (Moonraker, OctoPrint or PrusaLink; see
//! [`crate::output::host::send`]). The API key comes from the environment
//! (`P3DP_API_KEY`), never the command line, and is never printed; a
//! password in `--to` is used, never printed, and warned about.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::base::error::{Error, Result};
use crate::output::host::send::{Address, Host, Target, MAX_TIMEOUT_S};

/// The environment variable that holds the host's API key.
pub(crate) const KEY_VAR: &str = "P3DP_API_KEY";

/// What `send` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The files, in order.
    pub(crate) files: Vec<PathBuf>,
    /// The host's base URL.
    pub(crate) to: String,
    /// Start printing the (last) file once it is there.
    pub(crate) print: bool,
    /// The host, when not found by asking it.
    pub(crate) host: Option<String>,
    /// Seconds the host may stay silent.
    pub(crate) timeout: u64,
}

/// Sends every file; one error per file that did not arrive (the others
/// are still sent). A file's line on standard output says where it went.
/// Every file is checked to be a regular file before the host is asked
/// anything: a FIFO, device or folder is refused unopened, and nothing is
/// sent.
pub(crate) fn run(a: &Options) -> Result<Vec<Error>> {
    if a.files.is_empty() {
        return Err(Error::input(
            "",
            "no file given; expected one or more FILEs to send",
        ));
    }
    if !(1..=MAX_TIMEOUT_S).contains(&a.timeout) {
        return Err(Error::input(
            "--timeout",
            format!(
                "{} s is not allowed; expected 1 to {MAX_TIMEOUT_S} s (how long the host may stay silent)",
                a.timeout
            ),
        ));
    }
    let address = Address::parse(&a.to)?;
    if address.has_credentials() {
        crate::tellln!(
            "warning: --to holds a user name and password: p3dp sends them but never prints them; a command line is seen by other users (ps) and kept in shell history: put the host's API key in {KEY_VAR} instead"
        );
    }
    let bad: Vec<Error> = a.files.iter().filter_map(|f| regular(f).err()).collect();
    if !bad.is_empty() {
        return Ok(bad);
    }
    let key = std::env::var(KEY_VAR).ok().filter(|k| !k.trim().is_empty());
    let target = Target {
        address,
        key: key.map(|k| k.trim().to_string()),
        timeout: Duration::from_secs(a.timeout),
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

/// Refuses `file` unless it is a regular file (its type read before it is
/// ever opened): a missing file, a FIFO, a device, a folder.
fn regular(file: &Path) -> Result<()> {
    let shown = file.display().to_string();
    std::fs::metadata(file).map_err(|e| Error::io_from(&shown, format!("cannot read: {e}"), &e))?;
    crate::base::input::check_regular(file, "file to send").map_err(|e| e.in_file(&shown))
}

/// Opens one file and streams it to the host with a progress bar on a
/// terminal.
fn send_one(target: &Target, host: Host, file: &Path, print: bool) -> Result<()> {
    let shown = file.display().to_string();
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| Error::input(shown.clone(), "not a file name"))?;
    // its type checked again, opened without blocking, checked once open
    let mut f =
        crate::base::input::open_regular(file, "file to send").map_err(|e| e.in_file(&shown))?;
    let size = f
        .metadata()
        .map_err(|e| Error::io_from(&shown, format!("cannot read: {e}"), &e))?
        .len();
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(size),
        indicatif::ProgressDrawTarget::stderr_with_hz(4),
    );
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:30} {bytes}/{total_bytes} {msg}")
    {
        bar.set_style(style);
    }
    bar.set_message(crate::base::safe_text::one_line(&name).into_owned());
    let sent = target.upload(host, &name, (&mut f, size), print, &mut |n, total| {
        bar.set_length(total);
        bar.set_position(n);
    });
    bar.finish_and_clear();
    let sent = sent.map_err(|e| Error {
        file: Some(shown.clone()),
        place: Some(format!(
            "sending to {} at {}",
            host.name(),
            target.address.shown()
        )),
        ..e
    })?;
    crate::sayln!(
        "{shown}: sent to {} at {} as {} ({size} bytes){}",
        host.name(),
        target.address.shown(),
        sent.path,
        if sent.printing { ", printing" } else { "" }
    );
    Ok(())
}
