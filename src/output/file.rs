//! Output files: written whole or not at all, never replacing a special
//! file, never one of the command's own inputs.
//!
//! A regular file (or a missing one) is written to a temp file beside it,
//! renamed over it on [`AtomicFile::commit`]. A symlink is followed and its
//! final target written that way (the link stays a link). A character device
//! (`/dev/null`) or a FIFO is written to directly; a folder, a block device
//! or a socket is refused. Temp files are named `.p3dp-XXXXXX.tmp`; those of
//! a run stopped by SIGINT, SIGTERM or SIGHUP are removed (see
//! [`remove_temp_files_on_signals`]), and those a SIGKILL left behind are
//! swept from a folder the next time p3dp writes there once they are
//! [`STALE_AFTER`] old (on a thread of its own, which the build does not
//! wait for).

use std::io::{self, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, SystemTime};

use sha2::{Digest, Sha256};

use crate::base::error::{Error, Result};

/// How old a temp file of our own naming must be before a later run removes it.
pub const STALE_AFTER: Duration = Duration::from_secs(3600);

/// Temp files being written now, removed when a signal stops the process.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Folders already swept of stale temp files by this process.
static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a command that stops cleanly by itself does with a signal, instead
/// of the exit of [`remove_temp_files_on_signals`]: given the signal, it
/// returns whether it took it.
pub type StopHook = Box<dyn FnOnce(i32) -> bool + Send>;

/// The hook of [`stop_on_signals`], taken by the first signal.
static ON_SIGNAL: Mutex<Option<StopHook>> = Mutex::new(None);

/// Removes every temp file being written and exits (128 + the signal) on
/// SIGINT, SIGTERM or SIGHUP; the first signal after [`stop_on_signals`]
/// goes to its hook instead. Called once by the binary.
pub fn remove_temp_files_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("p3dp-signals".into())
            .spawn(move || {
                for sig in signals.forever() {
                    let hook = ON_SIGNAL.lock().unwrap_or_else(|e| e.into_inner()).take();
                    if hook.is_some_and(|stop| stop(sig)) {
                        continue; // the command stops by itself; a second signal exits
                    }
                    // held until exit: no temp file is made or renamed after this
                    let files = live();
                    for f in files.iter() {
                        let _ = std::fs::remove_file(f);
                    }
                    std::process::exit(128 + sig);
                }
            });
    }
}

/// Lets a command that writes no files and stops cleanly by itself (`p3dp
/// watch`) take the next SIGINT, SIGTERM or SIGHUP: `stop` is called with it
/// instead of the exit (once: a second signal exits as usual).
pub fn stop_on_signals(stop: StopHook) {
    *ON_SIGNAL.lock().unwrap_or_else(|e| e.into_inner()) = Some(stop);
}

/// The extension of `path` in lower case ("" without one): what an output's
/// format is told by.
pub fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Whether `name` is one of our temp files: `.p3dp-` + 6 letters or digits + `.tmp`.
pub fn is_temp_name(name: &str) -> bool {
    name.strip_prefix(".p3dp-")
        .and_then(|r| r.strip_suffix(".tmp"))
        .is_some_and(|mid| mid.len() == 6 && mid.bytes().all(|b| b.is_ascii_alphanumeric()))
}

/// Removes temp files of our naming in `dir` older than [`STALE_AFTER`]
/// (left by a killed run); each folder once per process.
fn sweep_stale(dir: &Path) {
    let key = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    {
        let mut swept = SWEPT.lock().unwrap_or_else(|e| e.into_inner());
        if swept.contains(&key) {
            return;
        }
        swept.push(key);
    }
    // on a thread of its own, not waited for: reading a big folder (3,400
    // entries in /tmp: 2 ms) would hold up a small build, and a sweep cut
    // short by the process's end is harmless (it removes only old files of
    // our naming, one at a time)
    let dir = dir.to_path_buf();
    let spawned = std::thread::Builder::new()
        .name("p3dp-sweep".into())
        .spawn(move || sweep_now(&dir));
    drop(spawned); // no thread to spare: the next build sweeps
}

/// [`sweep_stale`]'s work, on the caller's thread.
fn sweep_now(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let now = SystemTime::now();
    for e in entries.flatten() {
        if !e.file_name().to_str().is_some_and(is_temp_name) {
            continue;
        }
        let Ok(meta) = e.path().symlink_metadata() else {
            continue;
        };
        let old = meta
            .modified()
            .ok()
            .and_then(|m| now.duration_since(m).ok())
            .is_some_and(|age| age > STALE_AFTER);
        if meta.is_file() && old {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Follows symlinks from `path` to the file they end at (which may be
/// missing); also returns its metadata when it exists.
fn follow(path: &Path) -> io::Result<(PathBuf, Option<std::fs::Metadata>)> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match p.symlink_metadata() {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&p)?;
                p = if to.is_absolute() {
                    to
                } else {
                    p.parent().unwrap_or(Path::new("")).join(to)
                };
            }
            Ok(m) => return Ok((p, Some(m))),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok((p, None)),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Whether the metadata is of a file written to directly: a character device or a FIFO.
fn is_stream(m: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = m.file_type();
        t.is_char_device() || t.is_fifo()
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        false
    }
}

enum Inner {
    Temp(tempfile::NamedTempFile),
    Direct(std::fs::File),
}

/// A writer that hashes and counts what passes through it. The hash is
/// taken of the buffer's chunks as they go out (64 KiB at a time), not of
/// each small write: the same bytes in the same order, so the same SHA-256,
/// without copying every G-code line into the hasher's block buffer.
pub struct HashWriter<W: Write> {
    inner: io::BufWriter<Hashed<W>>,
}

/// What [`HashWriter`]'s buffer writes to: the writer, hashing what it takes.
struct Hashed<W: Write> {
    out: W,
    hasher: Sha256,
    bytes: u64,
}

impl<W: Write> Write for Hashed<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.out.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

impl<W: Write> HashWriter<W> {
    /// Wraps `inner` (buffered).
    pub fn new(inner: W) -> HashWriter<W> {
        let hashed = Hashed {
            out: inner,
            hasher: Sha256::new(),
            bytes: 0,
        };
        HashWriter {
            inner: io::BufWriter::with_capacity(1 << 16, hashed),
        }
    }

    /// The SHA-256 in hex and the byte count.
    pub fn finish(self) -> (String, u64) {
        let (hex, bytes, _) = self.finish_into();
        (hex, bytes)
    }

    /// The SHA-256 in hex, the byte count and the inner writer (flushed
    /// before: the writer of the G-code flushes at its end).
    pub fn finish_into(self) -> (String, u64, W) {
        let hashed = self
            .inner
            .into_inner()
            .unwrap_or_else(|e| panic!("flushed before: {e}"));
        let d = hashed.hasher.finalize();
        let hex: String = d.iter().map(|b| format!("{b:02x}")).collect();
        (hex, hashed.bytes, hashed.out)
    }
}

impl<W: Write> Write for HashWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.inner.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.inner.write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// A file being written: a temp file beside its target, renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, it leaves nothing behind. A
/// character device or FIFO is written directly instead.
pub struct AtomicFile {
    inner: Option<Inner>,
    /// The file renamed over: the target with its symlinks followed.
    target: PathBuf,
    shown: String,
    /// The temp file's fsync begun when its writing ended ([`Streaming`]).
    sync: Option<std::sync::Arc<Fsync>>,
}

/// A temp file's fsync on a pool worker, begun when [`Streaming`] is
/// flushed at the end of the writing, so that it runs while the checks
/// finish and the commit waits for less of it (the sphere's took 0.5–0.9
/// ms of its 10). The commit still renames only after an fsync of every
/// byte: a write after it began cancels it (the commit syncs then), and
/// one not yet begun (every worker busy) is done by the commit itself.
#[derive(Default)]
struct Fsync {
    state: Mutex<FsyncState>,
    done: std::sync::Condvar,
}

/// Where an [`Fsync`] is.
#[derive(Default)]
enum FsyncState {
    #[default]
    Queued,
    Running,
    Done(io::Result<()>),
    /// Not to run: waited for before it began, or cancelled.
    Dropped,
}

impl Fsync {
    /// Queues an fsync of `file` on the pool.
    fn start(file: std::fs::File) -> std::sync::Arc<Fsync> {
        let sync = std::sync::Arc::new(Fsync::default());
        let job = sync.clone();
        rayon::spawn(move || {
            {
                let mut st = job.lock();
                if !matches!(*st, FsyncState::Queued) {
                    return;
                }
                *st = FsyncState::Running;
            }
            let r = file.sync_all();
            *job.lock() = FsyncState::Done(r);
            job.done.notify_all();
        });
        sync
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, FsyncState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Keeps it from beginning (one running goes on, unwaited for).
    fn cancel(&self) {
        let mut st = self.lock();
        if matches!(*st, FsyncState::Queued) {
            *st = FsyncState::Dropped;
        }
    }

    /// Its result, waiting for it if it is running; `None` when it had not
    /// begun (it never will: the caller syncs the file itself).
    fn wait(&self) -> Option<io::Result<()>> {
        let mut st = self.lock();
        loop {
            match std::mem::replace(&mut *st, FsyncState::Dropped) {
                FsyncState::Queued | FsyncState::Dropped => return None,
                FsyncState::Done(r) => return Some(r),
                FsyncState::Running => {
                    *st = FsyncState::Running;
                    st = self.done.wait(st).unwrap_or_else(|e| e.into_inner());
                }
            }
        }
    }
}

impl AtomicFile {
    /// Opens a temp file in `target`'s folder (which must exist), or the
    /// target itself when it is a character device or a FIFO.
    pub fn create(target: &Path) -> Result<AtomicFile> {
        let shown = target.display().to_string();
        if target.as_os_str().is_empty() {
            return Err(Error::input(
                "",
                "an empty file name; expected the name of a file to write",
            ));
        }
        let (real, meta) =
            follow(target).map_err(|e| Error::io(&shown, format!("cannot write: {e}")))?;
        if let Some(m) = &meta {
            if m.is_dir() {
                return Err(Error::io(
                    &shown,
                    "cannot write: it is a folder; expected a file",
                ));
            }
            if is_stream(m) {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&real)
                    .map_err(|e| Error::io(&shown, format!("cannot write: {e}")))?;
                return Ok(AtomicFile {
                    inner: Some(Inner::Direct(f)),
                    target: real,
                    shown,
                    sync: None,
                });
            }
            if !m.is_file() {
                return Err(Error::io(
                    &shown,
                    "cannot write: it is neither a regular file, a character device nor a FIFO",
                ));
            }
        }
        let dir = match real.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        sweep_stale(&dir);
        let mut builder = tempfile::Builder::new();
        builder.prefix(".p3dp-").suffix(".tmp").rand_bytes(6);
        #[cfg(unix)]
        {
            // an ordinary file (0666 less the umask), not tempfile's private 0600
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let mut files = live();
        let tmp = builder.tempfile_in(&dir).map_err(|e| {
            Error::io(
                &shown,
                format!("cannot create a file in {}: {e}", dir.display()),
            )
        })?;
        files.push(tmp.path().to_path_buf());
        Ok(AtomicFile {
            inner: Some(Inner::Temp(tmp)),
            target: real,
            shown,
            sync: None,
        })
    }

    /// The file to write to.
    pub fn file(&mut self) -> &mut std::fs::File {
        match self.inner.as_mut().expect("not committed") {
            Inner::Temp(t) => t.as_file_mut(),
            Inner::Direct(f) => f,
        }
    }

    /// The file to write a big output to: as [`AtomicFile::file`], with the
    /// kernel asked to start writing each 2 MB to disk as it is written.
    pub fn streaming(&mut self) -> Streaming<'_> {
        let kick = matches!(self.inner, Some(Inner::Temp(_)));
        let file = match self.inner.as_mut().expect("not committed") {
            Inner::Temp(t) => t.as_file_mut(),
            Inner::Direct(f) => f,
        };
        Streaming {
            file,
            kick,
            written: 0,
            kicked: 0,
            sync: &mut self.sync,
        }
    }

    /// Flushes to disk and renames the temp file to the target.
    pub fn commit(mut self) -> Result<()> {
        let shown = self.shown.clone();
        let io = |e: io::Error| Error::io_from(&shown, format!("cannot write: {e}"), &e);
        match self.inner.take().expect("committed once") {
            Inner::Direct(mut f) => f.flush().map_err(io),
            Inner::Temp(mut t) => {
                let path = t.path().to_path_buf();
                // the fsync begun when the writing ended, else one now
                let synced = self.sync.take().and_then(|s| s.wait());
                let r = synced
                    .unwrap_or_else(|| t.as_file_mut().sync_all())
                    .map_err(io)
                    .and_then(|_| t.persist(&self.target).map(|_| ()).map_err(|e| io(e.error)));
                live().retain(|p| *p != path);
                r
            }
        }
    }
}

/// [`AtomicFile::streaming`]: every [`Streaming::KICK`] bytes, a
/// `sync_file_range(SYNC_FILE_RANGE_WRITE)` on the bytes before (Linux; it
/// starts the write-out and does not wait), so the commit's fsync has little
/// left to do. Elsewhere, and on a FIFO or device, a plain file.
pub struct Streaming<'a> {
    file: &'a mut std::fs::File,
    kick: bool,
    written: u64,
    kicked: u64,
    /// The file's [`Fsync`], begun by the flush at the end of the writing.
    sync: &'a mut Option<std::sync::Arc<Fsync>>,
}

impl Streaming<'_> {
    /// How many bytes are written between two kicks.
    pub const KICK: u64 = 2 << 20;

    #[cfg(target_os = "linux")]
    fn start_write_out(&self) {
        use std::os::fd::AsRawFd;
        // SAFETY: a plain system call on a file descriptor we hold open; it
        // reads no memory of ours. Its result is only advice, so ignored.
        unsafe {
            libc::sync_file_range(
                self.file.as_raw_fd(),
                self.kicked as libc::off64_t,
                (self.written - self.kicked) as libc::off64_t,
                libc::SYNC_FILE_RANGE_WRITE,
            );
        }
    }

    #[cfg(not(target_os = "linux"))]
    fn start_write_out(&self) {}
}

impl Write for Streaming<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if let Some(s) = self.sync.take() {
            s.cancel(); // written after: the commit syncs it all
        }
        let n = self.file.write(buf)?;
        self.written += n as u64;
        if self.kick && self.written - self.kicked >= Self::KICK {
            self.start_write_out();
            self.kicked = self.written;
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        // the end of the writing: the rest goes out while the checks finish
        if self.kick && self.written > self.kicked {
            self.start_write_out();
            self.kicked = self.written;
        }
        self.file.flush()?;
        // and is made durable meanwhile, on a pool worker (see Fsync)
        if self.kick && self.sync.is_none() {
            if let Ok(f) = self.file.try_clone() {
                *self.sync = Some(Fsync::start(f));
            }
        }
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(s) = self.sync.take() {
            s.cancel(); // no fsync for a file about to go
        }
        if let Some(Inner::Temp(t)) = self.inner.take() {
            let path = t.path().to_path_buf();
            drop(t); // removes the temp file
            live().retain(|p| *p != path);
        }
    }
}

/// Writes `target` atomically: a temp file beside it, renamed on success.
pub fn write_atomic(target: &Path, f: impl FnOnce(&mut std::fs::File) -> Result<()>) -> Result<()> {
    let mut a = AtomicFile::create(target)?;
    f(a.file())?;
    a.commit()
}

/// What `path` names once symlinks, `.` and `..` are resolved, whether or
/// not it exists: two paths with the same identity are the same file.
pub fn identity(path: &Path) -> PathBuf {
    let followed = follow(path)
        .map(|(p, _)| p)
        .unwrap_or_else(|_| path.to_path_buf());
    if let Ok(c) = followed.canonicalize() {
        return c;
    }
    let abs = if followed.is_absolute() {
        followed
    } else {
        std::env::current_dir().unwrap_or_default().join(followed)
    };
    // the longest existing ancestor, canonical, then the rest lexically
    let comps: Vec<Component> = abs.components().collect();
    for k in (0..comps.len()).rev() {
        let head: PathBuf = comps[..k].iter().collect();
        if let Ok(mut out) = head.canonicalize() {
            for c in &comps[k..] {
                match c {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    other => out.push(other.as_os_str()),
                }
            }
            return out;
        }
    }
    abs
}

/// Whether `path` is a character device or FIFO (written directly, so
/// several outputs may share it, like `/dev/null`).
fn is_shared_stream(path: &Path) -> bool {
    matches!(follow(path), Ok((_, Some(m))) if is_stream(&m))
}

/// Refuses outputs that resolve to the same file as another output or as
/// one of the command's `inputs`; each is `(option, path)`, e.g.
/// `("--stats-json", "s.json")`. Called before anything is written.
pub fn check_distinct(outputs: &[(String, PathBuf)], inputs: &[(String, PathBuf)]) -> Result<()> {
    let ids: Vec<Option<PathBuf>> = outputs
        .iter()
        .map(|(_, p)| (!is_shared_stream(p)).then(|| identity(p)))
        .collect();
    let inputs: Vec<(&String, &PathBuf, PathBuf)> =
        inputs.iter().map(|(l, p)| (l, p, identity(p))).collect();
    // the first output of each identity (a batch may have 10,000)
    let mut first: std::collections::HashMap<&PathBuf, usize> = std::collections::HashMap::new();
    for (k, (label, path)) in outputs.iter().enumerate() {
        let Some(id) = &ids[k] else { continue };
        if let Some((what, input, _)) = inputs.iter().find(|(_, _, i)| i == id) {
            return Err(Error::input(
                label.as_str(),
                format!(
                    "`{}` is {what} `{}`, which this command reads; expected another file to write",
                    path.display(),
                    input.display()
                ),
            ));
        }
        if let Some(&j) = first.get(id) {
            return Err(Error::input(
                label.as_str(),
                format!(
                    "`{}` is the file {} `{}` writes too; expected a different file for each output",
                    path.display(),
                    outputs[j].0,
                    outputs[j].1.display()
                ),
            ));
        }
        first.insert(id, k);
    }
    Ok(())
}

/// Set once standard output is a closed pipe (`p3dp build … -o - | head -1`).
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Whether a write to [`Stdout`] found the pipe closed: the reader has all it
/// wanted, and the command ends quietly with status 0, as `rg` does.
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::Relaxed)
}

/// Standard output that notes a closed pipe (see [`stdout_closed`]).
pub struct Stdout;

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        io::stdout().lock().write(buf).inspect_err(note_closed)
    }
    fn flush(&mut self) -> io::Result<()> {
        io::stdout().lock().flush().inspect_err(note_closed)
    }
}

/// Writes to standard output through [`Stdout`]: a closed pipe
/// (`p3dp check … | head -1`) is noted, never a panic as `print!`'s is.
pub fn say_fmt(args: std::fmt::Arguments) {
    if !stdout_closed() {
        let _ = Stdout.write_fmt(args);
    }
}

/// Writes to standard error; a closed one is ignored, never a panic as
/// `eprint!`'s is.
pub fn tell_fmt(args: std::fmt::Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// `print!` that ends quietly on a closed pipe (see [`say_fmt`]).
#[macro_export]
macro_rules! say {
    ($($t:tt)*) => { $crate::output::file::say_fmt(format_args!($($t)*)) };
}

/// `println!` that ends quietly on a closed pipe (see [`say_fmt`]).
#[macro_export]
macro_rules! sayln {
    ($($t:tt)*) => { $crate::output::file::say_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

/// `eprint!` that never panics (see [`tell_fmt`]).
#[macro_export]
macro_rules! tell {
    ($($t:tt)*) => { $crate::output::file::tell_fmt(format_args!($($t)*)) };
}

/// `eprintln!` that never panics (see [`tell_fmt`]).
#[macro_export]
macro_rules! tellln {
    ($($t:tt)*) => { $crate::output::file::tell_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

fn note_closed(e: &io::Error) {
    if e.kind() == io::ErrorKind::BrokenPipe {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names_are_ours_only() {
        assert!(is_temp_name(".p3dp-a1B2c3.tmp"));
        assert!(!is_temp_name(".p3dp-a1B2c.tmp"));
        assert!(!is_temp_name("p3dp-a1B2c3.tmp"));
        assert!(!is_temp_name(".p3dp-a1B2c3.tmp.gcode"));
    }

    #[test]
    fn identity_resolves_dots_of_missing_paths() {
        let d = std::env::temp_dir().canonicalize().unwrap();
        assert_eq!(
            identity(&d.join("no-such-p3dp-dir/../x.gcode")),
            d.join("x.gcode")
        );
        assert_eq!(identity(&d.join("./y/./z")), d.join("y/z"));
    }

    #[test]
    fn a_streamed_file_is_every_byte_once_committed() {
        // past two kicks, in odd-sized writes: the kicks change no byte, and
        // nothing is at the target before the commit
        let dir = std::env::temp_dir().join(format!("p3dp-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("big.gcode");
        let bytes: Vec<u8> = (0..(2 * Streaming::KICK + 12_345))
            .map(|k| (k % 251) as u8)
            .collect();
        let mut f = AtomicFile::create(&target).unwrap();
        let mut w = f.streaming();
        for piece in bytes.chunks(65_537) {
            w.write_all(piece).unwrap();
        }
        w.flush().unwrap();
        assert!(!target.exists());
        f.commit().unwrap();
        assert!(std::fs::read(&target).unwrap() == bytes);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bytes_written_after_the_early_fsync_are_committed_too() {
        // a flush begins the fsync on the pool; a write after it cancels it
        // (or lets it finish unwaited for), and the commit syncs it all
        let dir = std::env::temp_dir().join(format!("p3dp-fsync-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.gcode");
        let mut f = AtomicFile::create(&target).unwrap();
        {
            let mut w = f.streaming();
            w.write_all(b"G1 X1\n").unwrap();
            w.flush().unwrap();
            w.write_all(b"G1 X2\n").unwrap();
            w.flush().unwrap();
        }
        assert!(f.sync.is_some(), "the last flush began an fsync");
        f.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"G1 X1\nG1 X2\n");
        // an fsync still queued when the file is dropped never runs on it
        let mut g = AtomicFile::create(&dir.join("gone.gcode")).unwrap();
        g.streaming().flush().unwrap();
        drop(g);
        assert!(!dir.join("gone.gcode").exists());
        // waited for before it begins: the caller syncs itself
        let s = Fsync::default();
        assert!(s.wait().is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
