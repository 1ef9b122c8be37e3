//! Where a command's table goes, checked before any work is done, and what the input carries
//! to it beside the computed columns.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use mls_io::{Attribute, Column, FileFormat, LasTemplate, PlyFormat};

use crate::pipeline::{STDOUT_NAME, format_name, input_name, is_stdio};

/// The column PLY output repeats as the vertex property `quality`, the one per-vertex value
/// MeshLab reads from PLY ([`mls_io::WriteOptions::ply_quality`]): the mean curvature.
pub const PLY_QUALITY: &str = "mean";

/// Where a command's table goes.
#[derive(Debug)]
pub enum Output {
    /// A file, written atomically.
    File(PathBuf, FileFormat),
    /// Standard output (`-o -`).
    Stdout(FileFormat),
}

impl Output {
    pub fn format(&self) -> FileFormat {
        match self {
            Self::File(_, f) | Self::Stdout(f) => *f,
        }
    }

    /// The name for the summary and messages.
    pub fn name(&self) -> String {
        match self {
            Self::File(path, _) => path.display().to_string(),
            Self::Stdout(_) => STDOUT_NAME.to_owned(),
        }
    }

    /// Writes the table; PLY in binary little endian unless `ascii`; LAS in the layout of
    /// the LAS input `las`, if given.
    pub fn write(
        &self,
        columns: &[Column<'_>],
        ascii: bool,
        las: Option<&LasTemplate>,
    ) -> Result<()> {
        let options = mls_io::WriteOptions {
            ply_format: if ascii {
                PlyFormat::Ascii
            } else {
                PlyFormat::BinaryLittleEndian
            },
            las,
            ply_quality: Some(PLY_QUALITY),
        };
        match self {
            Self::File(path, format) => {
                mls_io::write_point_cloud_as_with(path, *format, columns, &options)?;
            }
            Self::Stdout(format) => {
                let written = mls_io::write_point_cloud_to_with(
                    std::io::stdout().lock(),
                    STDOUT_NAME,
                    *format,
                    columns,
                    &options,
                );
                match written {
                    Err(mls_io::WriteError::Io { error, .. })
                        if error.kind() == std::io::ErrorKind::BrokenPipe =>
                    {
                        quit_on_broken_pipe();
                    }
                    other => other?,
                }
            }
        }
        Ok(())
    }
}

/// The reader of standard output has gone (`mlscurv … -o - | head`): stop quietly and
/// successfully, as a program killed by SIGPIPE would stop, without a message about it.
fn quit_on_broken_pipe() -> ! {
    std::process::exit(0)
}

/// Writes to standard output, quitting quietly if the reader has gone.
pub fn write_stdout(bytes: &[u8]) -> Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(bytes).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => quit_on_broken_pipe(),
        other => other.map_err(|e| anyhow!("{STDOUT_NAME}: {e}")),
    }
}

/// Checks the output before any work is done, so that a long run does not end in an error
/// the command line already showed: `-` is standard output in `format` (default
/// `stdout_default`, else CSV); a file must not be one of the `inputs`, must have a known
/// extension that agrees with `format`, must not be a directory, must be in an existing
/// directory, and must not be read-only unless `force`.
pub fn check_output(
    inputs: &[&Path],
    path: &Path,
    format: Option<FileFormat>,
    force: bool,
    ascii: bool,
    stdout_default: Option<FileFormat>,
) -> Result<Output> {
    if format == Some(FileFormat::E57) || FileFormat::from_path(path) == Some(FileFormat::E57) {
        bail!(
            "{}: E57 is an input format only; write .ply, .csv, .xyz, .las or .laz",
            if is_stdio(path) {
                STDOUT_NAME.to_owned()
            } else {
                path.display().to_string()
            }
        );
    }
    // The LAS header's date comes from SOURCE_DATE_EPOCH when it is set: a bad value is
    // refused now, not when the header is written.
    let las_date = |format: FileFormat, name: &dyn std::fmt::Display| -> Result<()> {
        if matches!(format, FileFormat::Las | FileFormat::Laz) {
            mls_io::las_creation_date().map_err(|e| anyhow!("{name}: {e}"))?;
        }
        Ok(())
    };
    if is_stdio(path) {
        let format = format.or(stdout_default).unwrap_or(FileFormat::Csv);
        las_date(format, &STDOUT_NAME)?;
        if format == FileFormat::Ply && !ascii && std::io::stdout().is_terminal() {
            bail!(
                "{STDOUT_NAME}: refusing to write binary PLY to a terminal; redirect it, or add --ascii"
            );
        }
        if matches!(format, FileFormat::Las | FileFormat::Laz) && std::io::stdout().is_terminal() {
            bail!("{STDOUT_NAME}: refusing to write binary LAS/LAZ to a terminal; redirect it");
        }
        return Ok(Output::Stdout(format));
    }
    let name = path.display();
    for input in inputs {
        if !is_stdio(input) && mls_io::same_file(input, path) {
            bail!("{name}: output path is the input file; refusing to overwrite it");
        }
    }
    let existing = std::fs::metadata(path).ok();
    if existing.as_ref().is_some_and(std::fs::Metadata::is_dir) {
        bail!("{name}: is a directory; expected an output file name");
    }
    let format = match (format, FileFormat::from_path(path)) {
        (Some(given), Some(by_extension)) if given != by_extension => bail!(
            "{name}: --output-format {} disagrees with the file's extension, which means {}",
            format_name(given),
            format_name(by_extension)
        ),
        (Some(format), _) | (None, Some(format)) => format,
        (None, None) => bail!(
            "{name}: {}; expected .ply, .csv, .xyz, .txt, .pts, .asc, .las or .laz, or name the format with --output-format ply|xyz|csv|las|laz",
            match path.extension() {
                Some(e) => format!("unknown extension \".{}\"", e.to_string_lossy()),
                None => "no file extension".to_owned(),
            }
        ),
    };
    las_date(format, &name)?;
    check_replaceable(path, existing.as_ref(), force)?;
    Ok(Output::File(path.to_path_buf(), format))
}

/// What an input carries to the output of a command beside its geometry: its attributes
/// (colour, intensity, LAS dimensions …) and, for a LAS input, its layout.
#[derive(Debug, Default)]
pub struct Carried {
    pub attributes: Vec<Attribute>,
    pub las: Option<LasTemplate>,
}

impl Carried {
    /// What `cloud` carries, or nothing with `--no-attributes` (`keep` false).
    pub fn new(attributes: Vec<Attribute>, las: Option<LasTemplate>, keep: bool) -> Self {
        if keep {
            Self { attributes, las }
        } else {
            Self::default()
        }
    }

    /// Refuses, before any work is done, an attribute that `format` cannot hold: a LAS
    /// extra-bytes name has at most 32 bytes.
    pub fn check(&self, format: FileFormat, input: &Path) -> Result<()> {
        if !matches!(format, FileFormat::Las | FileFormat::Laz) {
            return Ok(());
        }
        if let Some(a) = self.attributes.iter().find(|a| a.name.len() > 32) {
            bail!(
                "{}: attribute `{}` has a name of {} bytes, but a LAS extra-bytes name holds at \
                 most 32; write another format, or leave the attributes out with \
                 --no-attributes",
                input_name(input),
                a.name,
                a.name.len()
            );
        }
        Ok(())
    }

    /// Renames the attributes whose names the output's own `columns` have (`k1` → `k1_in`),
    /// with one note on stderr naming them all, even with --quiet: a script reading the output
    /// by name needs to know. With a `mean` column, `quality` is the output's own too: PLY
    /// output repeats `mean` as `quality` ([`PLY_QUALITY`]), and an input's `quality` (such
    /// as an earlier output's) would otherwise take its place.
    pub fn rename_clashes(&mut self, columns: &[Column<'_>], input: &Path) {
        let mut reserved: Vec<&str> = columns.iter().map(|c| c.name).collect();
        if reserved.contains(&PLY_QUALITY) {
            reserved.push("quality");
        }
        let renamed = mls_io::rename_clashes(&mut self.attributes, &reserved);
        if renamed.is_empty() {
            return;
        }
        let list: Vec<String> = renamed
            .iter()
            .map(|(old, new)| format!("`{old}` as `{new}`"))
            .collect();
        eprintln!(
            "mlscurv: note: {}: the output has columns of these names of its own, so the \
             input's attributes are written as: {}",
            input_name(input),
            list.join(", ")
        );
    }

    /// `columns` with the attributes after the first `after` (the geometry); call
    /// [`Self::rename_clashes`] with the same columns first.
    pub fn insert<'a>(&'a self, mut columns: Vec<Column<'a>>, after: usize) -> Vec<Column<'a>> {
        let at = after.min(columns.len());
        columns.splice(at..at, self.attributes.iter().map(Column::attribute));
        columns
    }
}

/// Checks a file output path whose directory must exist: that directory exists, and an
/// `existing` file is replaced only when writable or `force` (its permissions are kept), and
/// a file can be created in the directory of the file a symbolic link points to.
pub fn check_replaceable(
    path: &Path,
    existing: Option<&std::fs::Metadata>,
    force: bool,
) -> Result<()> {
    let name = path.display();
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => bail!("{name}: {} is not a directory", dir.display()),
        Err(e) => bail!("{name}: directory {}: {e}", dir.display()),
    }
    if let Some(meta) = existing {
        // `readonly` is the mode alone (root could write anyway); opening for writing, without
        // truncating, asks the operating system whether this user may write to the file.
        let denied = meta.permissions().readonly()
            || std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .is_err_and(|e| e.kind() == std::io::ErrorKind::PermissionDenied);
        if denied && !force {
            bail!(
                "{name}: the file is read-only; refusing to replace it (add --force to replace it, keeping its permissions)"
            );
        }
    }
    // As the writer will: a temporary file created (and here removed) in the directory of
    // the file a link points to, so that a directory this user cannot write to is found now
    // rather than after the computation.
    mls_io::check_writable(path)?;
    Ok(())
}
