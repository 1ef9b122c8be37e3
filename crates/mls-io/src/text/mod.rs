//! Readers for the plain-text formats: XYZ/TXT/PTS (columns separated by whitespace, commas or
//! semicolons) and CSV with a header.

use std::io::BufRead;

use crate::attributes::{Attribute, TextColumn};
use crate::columns::{ColumnNames, ReadOptions, UNIT_TOLERANCE};
use crate::error::{ReadError, quoted};
use crate::lines::{Lines, parse_finite};
use crate::{CloudBuilder, PointCloud, ReadOutcome, SLOT_NAMES};

/// Reads rows of `x y z` (separated by whitespace, commas or semicolons), optionally followed
/// by normals and other columns, with the default options; see [`read_xyz_with`]. What the
/// reader noticed (columns ignored, columns 4–6 not taken as normals) is dropped: use
/// [`read_xyz_with`] to show it.
///
/// # Errors
/// As [`read_xyz_with`].
pub fn read_xyz(reader: impl BufRead, name: &str) -> Result<PointCloud, ReadError> {
    read_xyz_with(reader, name, &ReadOptions::default()).map(|r| r.cloud)
}

/// What a column of a headerless text file is read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// A slot of [`SLOT_NAMES`], parsed strictly.
    Slot(usize),
    /// Component `k` of the candidate normals (columns 4–6 without `--columns`), and
    /// attribute column `i` if they turn out not to be normals.
    Candidate(usize, usize),
    /// Attribute column `i`.
    Attribute(usize),
    /// Skipped, not parsed (a column named `_`).
    Skip,
}

/// The attribute columns of a text file, by name, on their way to [`Attribute`]s.
#[derive(Debug, Default)]
struct TextAttributes(Vec<(String, usize, TextColumn)>);

impl TextAttributes {
    /// Adds a column for file column `column` (1-based); returns its index.
    fn add(&mut self, name: String, column: usize) -> usize {
        self.0.push((name, column, TextColumn::new()));
        self.0.len() - 1
    }

    fn push(&mut self, i: usize, line: usize, token: &str) {
        if let Some((_, _, c)) = self.0.get_mut(i) {
            c.push(line, token);
        }
    }

    /// The attributes, in column order, except those `skip` says; a column that holds
    /// something other than numbers is dropped with a note.
    fn finish(
        self,
        file: &str,
        skip: impl Fn(usize) -> bool,
        notes: &mut Vec<String>,
    ) -> Vec<Attribute> {
        let mut attributes = Vec::with_capacity(self.0.len());
        for (i, (name, column, values)) in self.0.into_iter().enumerate() {
            if skip(i) {
                continue;
            }
            match values.finish() {
                Ok(data) => attributes.push(Attribute { name, data }),
                Err((line, token)) => notes.push(format!(
                    "{file}: column {column} ({name}) is not carried to the output: line \
                     {line} holds {}, not a number",
                    quoted(&token)
                )),
            }
        }
        attributes
    }
}

/// Whether columns 4–6 of a headerless file hold unit vectors on every row so far.
#[derive(Debug, Default)]
struct UnitCheck {
    normals: Vec<[f64; 3]>,
    /// Why they are not normals: the first row that is not a unit vector, and what it holds.
    failed: Option<(usize, String)>,
    any_unit: bool,
}

impl UnitCheck {
    fn push(&mut self, line: usize, value: Result<[f64; 3], String>) {
        if self.failed.is_some() {
            return;
        }
        let why = match value {
            Ok(v) => {
                let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if v == [0.0; 3] || v.iter().all(|c| c.is_nan()) {
                    // A missing normal, kept as zero.
                    self.normals.push([0.0; 3]);
                    return;
                }
                if (length - 1.0).abs() <= UNIT_TOLERANCE {
                    self.any_unit = true;
                    self.normals.push(v);
                    return;
                }
                format!("{} {} {} has length {length:.6}", v[0], v[1], v[2])
            }
            Err(why) => why,
        };
        self.failed = Some((line, why));
        // Not normals: their memory is not needed.
        self.normals = Vec::new();
    }
}

/// Reads rows of columns (`.xyz`, `.txt`, `.pts`, `.asc`) and reports what it noticed. Columns are
/// separated by whitespace, or by commas or semicolons where the first row of values or
/// names is (CloudCompare's ASCII export writes either); every row takes that separator.
///
/// Blank lines and lines whose first non-blank character is `#` are ignored. A first data
/// row holding a single non-negative integer is the point-count line some scanners write at
/// the top of `.pts` files (and CloudCompare after its header), and is skipped. The first
/// data row fixes the column count; every later row must have as many. A `//` line before
/// the rows names the columns, split as the rows are (by tabs where both have them), as
/// CloudCompare writes it, as does a first row of which no field is a number, or else the
/// last `#` comment before the rows when it has one valid name per column. Such names are
/// read as [`read_csv`] reads a header's: `x y z nx ny nz` case-insensitively, the others
/// keeping their case with each character other than a letter, digit, `_`, `-` or `.` as
/// `_` (CloudCompare's `Mean curvature (0.4)` is `Mean_curvature__0.4_`). The columns are
/// read by this rule:
///
/// - With [`ReadOptions::columns`], by those names: the count must match, `x y z` and
///   `nx ny nz` (if named) are geometry, columns named `_` are skipped unparsed, and every
///   other column is an attribute of that name.
/// - Otherwise columns 1–3 are `x y z` (fewer than 3 columns is an error). Columns 4–6 of a
///   file of 6 columns or more are read as normals only if on **every** row they form a unit
///   vector, `|length − 1| ≤` [`UNIT_TOLERANCE`], or are `0 0 0` or `nan nan nan` (a missing
///   normal, read as `0 0 0`), with at least one unit row. Otherwise (colours `r g b` as
///   0–255 integers or 0–1 fractions, intensities) they are not normals, and a note names
///   them, the first row that is not a unit vector, and the way to name the columns. Every
///   column that is not geometry is an attribute named `colN` for column `N`, with a note.
///
/// An attribute column is `int32` when every value is an integer in its range, `int64` when
/// every value is an integer, `float64` otherwise; a column holding something other than
/// numbers (text, an empty field) is dropped with a note naming the first such value.
///
/// `name` is the display name used in errors and notes; each note is one line starting
/// with it.
///
/// # Errors
/// [`ReadError::UnsupportedColumnCount`] for fewer than 3 columns, [`ReadError::RasterGrid`]
/// for an ESRI ASCII grid,
/// [`ReadError::ColumnsMismatch`] when the named columns do not match the file,
/// [`ReadError::ColumnCount`], [`ReadError::Ascii`] for an `x y z` (or named normal) value
/// that is not a finite number or for text that is not UTF-8, and [`ReadError::Io`].
pub fn read_xyz_with(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
) -> Result<ReadOutcome, ReadError> {
    read_xyz_slots(reader, name, options, &SLOT_NAMES)
}

/// How the columns of a plain-text row are separated: by whitespace (the XYZ convention), or
/// by a comma or a semicolon, which CloudCompare's ASCII export offers too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Separator {
    Whitespace,
    Char(char),
}

impl Separator {
    /// The separator of `row`: a comma or a semicolon where splitting on it gives at least 3
    /// fields whose first three are numbers (a row of values), or names, none a number and
    /// none with a space inside (a row of names); else whitespace. Decimal commas
    /// (`1,5 2,3 3,1`) split into fields that are not numbers, so such a row stays
    /// whitespace-separated and is refused as not numbers; so does a whitespace-separated row
    /// with commas in a text column (`1 2 3 a,b,c`).
    fn of(row: &str) -> Self {
        for c in [',', ';'] {
            let fields: Vec<&str> = row.split(c).map(str::trim).collect();
            if fields.len() < 3 {
                continue;
            }
            let number = |f: &&str| f.parse::<f64>().is_ok();
            let name = |f: &&str| !f.is_empty() && !f.contains(char::is_whitespace);
            if fields[..3].iter().all(number)
                || (fields.iter().all(name) && !fields.iter().any(number))
            {
                return Self::Char(c);
            }
        }
        Self::Whitespace
    }

    /// The fields of `row`, trimmed of surrounding whitespace.
    fn fields(self, row: &str) -> Fields<'_> {
        match self {
            Self::Whitespace => Fields::Whitespace(row.split_ascii_whitespace()),
            Self::Char(c) => Fields::Char(row.split(c)),
        }
    }
}

/// The iterator of [`Separator::fields`].
enum Fields<'a> {
    Whitespace(std::str::SplitAsciiWhitespace<'a>),
    Char(std::str::Split<'a, char>),
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        match self {
            Self::Whitespace(fields) => fields.next(),
            Self::Char(fields) => fields.next().map(str::trim),
        }
    }
}

/// The column names of a row of names (line `line` of `file`), split by `separator`; an
/// error says `what` the row was taken for.
fn names_row(
    row: &str,
    separator: Separator,
    file: &str,
    line: usize,
    what: &str,
) -> Result<ColumnNames, ReadError> {
    let fields: Vec<&str> = separator.fields(row).collect();
    ColumnNames::from_header(&fields).map_err(|message| ReadError::Header {
        file: file.to_owned(),
        line,
        message: format!("{what}: {message}"),
    })
}

/// The separator of a `//` header line, given the first row of values' separator `data`:
/// the same character; for whitespace-separated values, tabs if both have them (then the
/// names may hold spaces, as CloudCompare's tab-separated export writes them), else
/// whitespace (CloudCompare's space-separated export writes a space in a name as `_`).
fn header_separator(header: &str, data: Separator, row: &str) -> Separator {
    match data {
        Separator::Whitespace if header.contains('\t') && row.contains('\t') => {
            Separator::Char('\t')
        }
        other => other,
    }
}

/// [`read_xyz_with`], reading the leading [`SLOT_NAMES`] `slots` as geometry and any other
/// column as an attribute.
pub(crate) fn read_xyz_slots(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
    slots: &[&str],
) -> Result<ReadOutcome, ReadError> {
    let mut lines = Lines::new(reader, 0);
    let mut roles: Vec<Role> = Vec::new();
    let mut first_row = true;
    let mut cloud = CloudBuilder::new(false, 0);
    let mut check: Option<UnitCheck> = None;
    let mut attributes = TextAttributes::default();
    // Column names from the file itself: CloudCompare writes them as a comment before the
    // rows, `//X Y Z Nx Ny Nz`; `--columns` overrides them. Split once the first row of
    // values shows the separator.
    let mut named: Option<(ColumnNames, usize)> = None;
    let mut slashes: Option<(String, usize)> = None;
    // The last `#` comment before the first row: the names when it has one per column
    // (mlscurv writes `# x y z nx ny nz k1 ...`).
    let mut comment: Option<(String, usize)> = None;
    // Decided by each row until the first row of values, then kept for the file.
    let mut separator = Separator::Whitespace;
    while let Some((line, text)) = lines.next_line(name)? {
        if let Some(rest) = text.trim_start().strip_prefix('#') {
            if roles.is_empty() {
                comment = Some((rest.to_owned(), line));
            }
            continue;
        }
        if let Some(header) = text.trim_start().strip_prefix("//") {
            if roles.is_empty() && options.columns.is_none() && slashes.is_none() {
                slashes = Some((header.to_owned(), line));
            }
            continue;
        }
        if roles.is_empty() {
            separator = Separator::of(text);
        }
        let found = separator.fields(text).count();
        if roles.is_empty() {
            let is_count_line = found == 1
                && separator
                    .fields(text)
                    .next()
                    .is_some_and(|t| t.parse::<u64>().is_ok());
            let first = std::mem::replace(&mut first_row, false);
            if first && is_count_line {
                continue;
            }
            // A first row with no number among its tokens cannot be a point: it names the
            // columns, as a header row of other tools' text exports does without `//` or `#`.
            // Numbers written with a decimal comma are numbers here (refused below, saying so).
            let number = |t: &str| t.replacen(',', ".", 1).parse::<f64>().is_ok();
            if first && found >= 3 && !separator.fields(text).any(number) {
                if options.columns.is_none() && slashes.is_none() {
                    let what = "the first row names the columns";
                    let columns = names_row(text, separator, name, line, what)?;
                    named = Some((columns, line));
                }
                continue;
            }
            if let Some((header, at)) = slashes.take() {
                let split = header_separator(&header, separator, text);
                let what = "column names after `//`";
                named = Some((names_row(&header, split, name, at, what)?, at));
            }
            // CloudCompare's `.asc` is a point cloud; ESRI's `.asc` is a height raster,
            // which begins `ncols N`.
            let starts = |word: &str| {
                separator
                    .fields(text)
                    .next()
                    .is_some_and(|t| t.eq_ignore_ascii_case(word))
            };
            if first && starts("ncols") {
                return Err(ReadError::RasterGrid {
                    file: name.to_owned(),
                    line,
                });
            }
            if found < 3 {
                return Err(ReadError::UnsupportedColumnCount {
                    file: name.to_owned(),
                    line,
                    found,
                });
            }
            let by = match (&options.columns, &named) {
                (None, Some((_, at))) => format!("the `//` line {at}"),
                _ => "--columns".to_owned(),
            };
            if options.columns.is_none() && named.is_none() {
                named = comment.take().and_then(|(names, at)| {
                    let tokens: Vec<&str> = Separator::of(&names).fields(&names).collect();
                    let columns = ColumnNames::parse(&tokens.join(",")).ok()?;
                    (tokens.len() == found).then_some((columns, at))
                });
            }
            roles = match options.columns.as_ref().or(named.as_ref().map(|(c, _)| c)) {
                Some(columns) => {
                    if columns.len() != found {
                        return Err(ReadError::ColumnsMismatch {
                            file: name.to_owned(),
                            line,
                            found,
                            named: columns.to_string(),
                            by,
                        });
                    }
                    cloud = CloudBuilder::new(columns.has_normals() && slots.len() > 3, 0);
                    columns
                        .slots()
                        .into_iter()
                        .map(|slot| slot.filter(|&s| s < slots.len()))
                        .zip(columns.names())
                        .enumerate()
                        .map(|(c, (slot, name))| match slot {
                            Some(slot) => Role::Slot(slot),
                            None if name == "_" => Role::Skip,
                            None => Role::Attribute(attributes.add(name.clone(), c + 1)),
                        })
                        .collect()
                }
                None => {
                    let normals = found >= 6 && slots.len() > 3;
                    if normals {
                        check = Some(UnitCheck::default());
                    }
                    (0..found)
                        .map(|c| {
                            let name = format!("col{}", c + 1);
                            match c {
                                0..3 => Role::Slot(c),
                                3..6 if normals => {
                                    Role::Candidate(c - 3, attributes.add(name, c + 1))
                                }
                                _ => Role::Attribute(attributes.add(name, c + 1)),
                            }
                        })
                        .collect()
                }
            };
        }
        if found != roles.len() {
            return Err(ReadError::ColumnCount {
                file: name.to_owned(),
                line,
                found,
                expected: roles.len(),
            });
        }
        let mut values = [0.0; 6];
        let mut candidate: Result<[f64; 3], String> = Ok([0.0; 3]);
        for (column, (token, role)) in separator.fields(text).zip(&roles).enumerate() {
            match *role {
                Role::Slot(slot) => {
                    let value = parse_finite(token).map_err(|message| ReadError::Ascii {
                        file: name.to_owned(),
                        line,
                        field: format!(
                            "column {} ({})",
                            column + 1,
                            SLOT_NAMES.get(slot).copied().unwrap_or("?")
                        ),
                        message,
                    })?;
                    if let Some(dst) = values.get_mut(slot) {
                        *dst = value;
                    }
                }
                Role::Candidate(k, i) => {
                    attributes.push(i, line, token);
                    if let Ok(v) = &mut candidate {
                        // NaN is let through: `nan nan nan` is a missing normal, as the
                        // curvature output writes for a failed point.
                        match token.parse::<f64>() {
                            Ok(value) if !value.is_infinite() => {
                                if let Some(dst) = v.get_mut(k) {
                                    *dst = value;
                                }
                            }
                            _ => {
                                candidate = Err(format!(
                                    "column {} is {}",
                                    column + 1,
                                    crate::error::quoted(token)
                                ));
                            }
                        }
                    }
                }
                Role::Attribute(i) => attributes.push(i, line, token),
                Role::Skip => {}
            }
        }
        if let Some(check) = &mut check {
            check.push(line, candidate);
        }
        cloud.push(values);
    }
    let mut cloud = cloud.finish();
    let mut notes = Vec::new();
    let width = roles.len();
    let mut normals_found = false;
    if options.columns.is_none() && named.is_none() && width > 3 {
        if let Some(check) = check {
            match check.failed {
                None if check.any_unit => {
                    cloud.normals = Some(check.normals);
                    normals_found = true;
                }
                None => notes.push(format!(
                    "{name}: columns 4-6 are 0 0 0 on every row; not read as normals but \
                     carried as attributes col4 col5 col6"
                )),
                Some((line, why)) => notes.push(format!(
                    "{name}: columns 4-6 are not read as normals: normals must be unit vectors \
                     (|length - 1| <= {UNIT_TOLERANCE}) or 0 0 0 on every row, but line \
                     {line}: {why}; they are carried as attributes col4 col5 col6 (name them \
                     with --columns, e.g. x,y,z,r,g,b, or x,y,z,nx,ny,nz to read them as \
                     normals anyway)"
                )),
            }
        }
        // Columns 4-6 of a wider file are accounted for above.
        let unnamed_from = if width >= 6 { 7 } else { 4 };
        if width >= unnamed_from {
            let range = if width == unnamed_from {
                format!("column {width} is carried as attribute col{width}")
            } else {
                format!(
                    "columns {unnamed_from}-{width} are carried as attributes \
                     col{unnamed_from}-col{width}"
                )
            };
            notes.push(format!(
                "{name}: {width} columns; {range} (name the columns with --columns)"
            ));
        }
    }
    // The candidates' attribute columns, if they were taken as normals.
    let mut normal_columns = [usize::MAX; 3];
    if normals_found {
        for role in &roles {
            if let Role::Candidate(k, i) = *role
                && let Some(slot) = normal_columns.get_mut(k)
            {
                *slot = i;
            }
        }
    }
    cloud.attributes = attributes.finish(name, |i| normal_columns.contains(&i), &mut notes);
    Ok(ReadOutcome { cloud, notes })
}

mod csv;
pub(crate) use csv::read_csv_slots;
pub use csv::{read_csv, read_csv_with};
