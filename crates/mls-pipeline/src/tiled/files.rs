//! The files of a tiled run: sizes and memory, the temporary directory (removed on Ctrl-C),
//! and the tiles' files.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result};

/// The budget in bytes from the machine's available memory (Linux: `MemAvailable`), leaving a
/// fifth to the rest of the system; `None` where it cannot be read.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Parses a memory size: a number with an optional unit `B`, `K`/`KB`/`KiB`, `M`/`MiB`,
/// `G`/`GiB`, `T`/`TiB` (powers of 1024 for all), case-insensitive.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size such as 2GiB, 512M or 1500000000"))?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}` (use K, M, G or T)"
            ));
        }
    };
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{text}` is not a positive size"));
    }
    Ok(bytes as u64)
}

/// The directories to remove on Ctrl-C, and the outputs whose temporary files to remove.
static CLEANUP: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes the registered temporary directories and output files and exits with 130, as a
/// shell reports an interrupted command.
fn on_interrupt() {
    if let Ok(paths) = CLEANUP.lock() {
        for path in paths.iter() {
            if path.is_dir() {
                let _ = std::fs::remove_dir_all(path);
            } else if let (Some(dir), Some(name)) = (path.parent(), path.file_name()) {
                // The atomic writer's temporary file: `.NAME.XXXXXX.tmp` beside the output.
                let prefix = format!(".{}.", name.to_string_lossy());
                let dir = if dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    dir
                };
                for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
                    let n = entry.file_name().to_string_lossy().into_owned();
                    if n.starts_with(&prefix) && n.ends_with(".tmp") {
                        let _ = std::fs::remove_file(entry.path());
                    }
                }
            }
        }
    }
    eprintln!("mlscurv: interrupted; temporary files removed");
    std::process::exit(130);
}

/// The temporary directory of a run, removed when dropped and on Ctrl-C.
pub(super) struct Workspace {
    pub(super) dir: tempfile::TempDir,
}

impl Workspace {
    /// A new temporary directory in `parent`, not registered for removal on Ctrl-C: to
    /// check before any work that one can be made there.
    pub(super) fn probe(parent: &Path) -> Result<tempfile::TempDir> {
        tempfile::Builder::new()
            .prefix(".mlscurv-tiles-")
            .tempdir_in(parent)
            .with_context(|| {
                format!(
                    "{}: cannot create a temporary directory for the tiles (--temp-dir chooses \
                     another place)",
                    parent.display()
                )
            })
    }

    pub(super) fn new(parent: &Path, output: &Path) -> Result<Self> {
        let dir = Self::probe(parent)?;
        if let Ok(mut paths) = CLEANUP.lock() {
            paths.push(dir.path().to_path_buf());
            paths.push(output.to_path_buf());
        }
        // Once per process; a second run in the same process keeps the first handler.
        let _ = ctrlc::set_handler(on_interrupt);
        Ok(Self { dir })
    }

    pub(super) fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        if let Ok(mut paths) = CLEANUP.lock() {
            paths.clear();
        }
    }
}

/// At most this many tile files are open at once: a cloud of 10¹⁰ points in 2 GiB has
/// thousands of tiles, beyond the usual limit of 1,024 open files. Input order (scan lines)
/// visits few tiles at a time, so the least recently used file is the one to close.
const MAX_OPEN: usize = 256;

/// The index of the least recently used open file, to close.
fn least_recent<T>(open: &[Option<T>], stamp: &[u64]) -> Option<usize> {
    (0..open.len())
        .filter(|&i| open[i].is_some())
        .min_by_key(|&i| stamp[i])
}

/// Appends to one file per tile, at most [`MAX_OPEN`] open at once.
pub(super) struct TileWriters {
    paths: Vec<PathBuf>,
    open: Vec<Option<BufWriter<File>>>,
    stamp: Vec<u64>,
    clock: u64,
    count: usize,
}

impl TileWriters {
    /// Creates (empty) the files at `paths`.
    pub(super) fn create(paths: Vec<PathBuf>) -> Result<Self> {
        for p in &paths {
            File::create(p).with_context(|| p.display().to_string())?;
        }
        let n = paths.len();
        Ok(Self {
            paths,
            open: (0..n).map(|_| None).collect(),
            stamp: vec![0; n],
            clock: 0,
            count: 0,
        })
    }

    /// Appends `bytes` to tile `tile`'s file.
    pub(super) fn write(&mut self, tile: usize, bytes: &[u8]) -> Result<()> {
        self.clock += 1;
        self.stamp[tile] = self.clock;
        if self.open[tile].is_none() {
            if self.count == MAX_OPEN
                && let Some(i) = least_recent(&self.open, &self.stamp)
                && let Some(mut w) = self.open[i].take()
            {
                w.flush()
                    .with_context(|| self.paths[i].display().to_string())?;
                self.count -= 1;
            }
            let path = &self.paths[tile];
            let file = OpenOptions::new()
                .append(true)
                .open(path)
                .with_context(|| path.display().to_string())?;
            self.open[tile] = Some(BufWriter::with_capacity(1 << 16, file));
            self.count += 1;
        }
        if let Some(w) = self.open[tile].as_mut() {
            w.write_all(bytes)
                .with_context(|| self.paths[tile].display().to_string())?;
        }
        Ok(())
    }

    /// Flushes every open file.
    pub(super) fn finish(mut self) -> Result<()> {
        for (w, path) in self.open.iter_mut().zip(&self.paths) {
            if let Some(w) = w {
                w.flush().with_context(|| path.display().to_string())?;
            }
        }
        Ok(())
    }
}

/// Reads one file per tile front to back, at most [`MAX_OPEN`] open at once (a closed one is
/// reopened where it was left).
pub(super) struct TileReaders {
    paths: Vec<PathBuf>,
    offsets: Vec<u64>,
    open: Vec<Option<BufReader<File>>>,
    stamp: Vec<u64>,
    clock: u64,
    count: usize,
}

impl TileReaders {
    pub(super) fn new(paths: Vec<PathBuf>) -> Self {
        let n = paths.len();
        Self {
            paths,
            offsets: vec![0; n],
            open: (0..n).map(|_| None).collect(),
            stamp: vec![0; n],
            clock: 0,
            count: 0,
        }
    }

    /// Fills `buf` from tile `tile`'s file.
    pub(super) fn read_exact(&mut self, tile: usize, buf: &mut [u8]) -> Result<()> {
        self.clock += 1;
        self.stamp[tile] = self.clock;
        if self.open[tile].is_none() {
            if self.count == MAX_OPEN
                && let Some(i) = least_recent(&self.open, &self.stamp)
            {
                self.open[i] = None;
                self.count -= 1;
            }
            let path = &self.paths[tile];
            let mut file = File::open(path).with_context(|| path.display().to_string())?;
            file.seek(SeekFrom::Start(self.offsets[tile]))
                .with_context(|| path.display().to_string())?;
            self.open[tile] = Some(BufReader::with_capacity(1 << 16, file));
            self.count += 1;
        }
        if let Some(r) = self.open[tile].as_mut() {
            r.read_exact(buf).with_context(|| {
                format!("{}: a tile's file ends early", self.paths[tile].display())
            })?;
        }
        self.offsets[tile] += buf.len() as u64;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// More tiles than may be open: records written and read back interleaved, in an order
    /// that closes and reopens files, come back whole and in order.
    #[test]
    fn more_tiles_than_open_files_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let tiles = MAX_OPEN * 2 + 7;
        let paths: Vec<PathBuf> = (0..tiles)
            .map(|i| dir.path().join(format!("{i}")))
            .collect();
        let order = |k: usize| (k * 7919) % tiles;
        let mut w = TileWriters::create(paths.clone()).unwrap();
        for k in 0..tiles * 5 {
            w.write(order(k), &(k as u64).to_le_bytes()).unwrap();
        }
        w.finish().unwrap();
        let mut r = TileReaders::new(paths);
        for k in 0..tiles * 5 {
            let mut b = [0u8; 8];
            r.read_exact(order(k), &mut b).unwrap();
            assert_eq!(u64::from_le_bytes(b), k as u64);
        }
        let mut b = [0u8; 8];
        assert!(r.read_exact(0, &mut b).is_err(), "a file read past its end");
    }
}
