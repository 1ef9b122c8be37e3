//! Readers for the plain-text formats: XYZ/TXT/PTS (columns separated by whitespace, commas or
//! semicolons) and CSV with a header.

use std::io::BufRead;

use crate::attributes::{Attribute, AttributeData, TextColumn, TextColumnType};
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

/// What a pass over a text file does with its rows.
pub(crate) enum Pass<'s, E> {
    /// Keeps every row: a whole read.
    Whole,
    /// Keeps none: learns what each column is ([`TextSchema`]).
    Profile,
    /// Hands the rows on in clouds of at most `max` points, reading each column as the first
    /// pass's `schema` says.
    Batches {
        schema: &'s TextSchema,
        max: u64,
        sink: &'s mut dyn FnMut(PointCloud) -> Result<(), E>,
        handed: bool,
    },
}

impl<E> Pass<'_, E> {
    fn schema(&self) -> Option<&TextSchema> {
        match self {
            Self::Batches { schema, .. } => Some(schema),
            _ => None,
        }
    }
}

/// What a first pass over a text file learns, which depends on every row: each attribute
/// column's type (in the order the reader meets them; `None` for one dropped, or taken as
/// normals), whether columns 4–6 of a headerless file are normals, and the reader's notes.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct TextSchema {
    columns: Vec<Option<TextColumnType>>,
    normals: bool,
    notes: Vec<String>,
    /// Whether the file is CSV (a header row), not headerless XYZ.
    csv: bool,
}

/// One attribute column's values.
#[derive(Debug)]
enum Values {
    /// Of a type still to learn.
    Learn(TextColumn),
    /// Of the type a first pass learnt.
    Typed(TextColumnType, AttributeData),
    /// Not read: dropped, or taken as normals, by the first pass.
    Skip,
}

/// The attribute columns of a text file, by name, on their way to [`Attribute`]s.
#[derive(Debug)]
struct TextAttributes<'s> {
    columns: Vec<(String, usize, Values)>,
    /// Whether learning columns keep their values.
    keep: bool,
    /// The types a first pass learnt, for a pass in batches.
    schema: Option<&'s TextSchema>,
}

impl<'s> TextAttributes<'s> {
    fn new<E>(pass: &Pass<'s, E>) -> Self {
        Self {
            columns: Vec::new(),
            keep: matches!(pass, Pass::Whole),
            schema: match pass {
                Pass::Batches { schema, .. } => Some(*schema),
                _ => None,
            },
        }
    }

    /// Adds a column for file column `column` (1-based); returns its index.
    fn add(&mut self, name: String, column: usize) -> usize {
        let i = self.columns.len();
        let values = match self.schema {
            Some(schema) => match schema.columns.get(i).copied().flatten() {
                Some(t) => Values::Typed(t, AttributeData::with_capacity(t.ty, 0)),
                None => Values::Skip,
            },
            None => Values::Learn(TextColumn::new(self.keep)),
        };
        self.columns.push((name, column, values));
        i
    }

    fn push(&mut self, i: usize, file: &str, line: usize, token: &str) -> Result<(), ReadError> {
        match self.columns.get_mut(i) {
            Some((_, _, Values::Learn(c))) => c.push(line, token),
            Some((name, column, Values::Typed(t, data))) => {
                if t.push(data, line, token) {
                    return Ok(());
                }
                return Err(ReadError::Ascii {
                    file: file.to_owned(),
                    line,
                    field: format!("column {column} ({name})"),
                    message: format!(
                        "{} is not a value of the column's type {}: the file changed since it \
                         was first read",
                        quoted(token),
                        t.ty.name()
                    ),
                });
            }
            _ => {}
        }
        Ok(())
    }

    /// The values read since the last batch, as attributes, in column order.
    fn take_batch(&mut self) -> Vec<Attribute> {
        let mut attributes = Vec::new();
        for (name, _, values) in &mut self.columns {
            if let Values::Typed(t, data) = values {
                let data = std::mem::replace(data, AttributeData::with_capacity(t.ty, 0));
                attributes.push(Attribute {
                    name: name.clone(),
                    data,
                });
            }
        }
        attributes
    }

    /// The attributes (those kept, or of the last batch), in column order, except those
    /// `skip` says, and every column's type; a column that holds something other than
    /// numbers is dropped with a note (when its type is learnt).
    fn finish(
        mut self,
        file: &str,
        skip: impl Fn(usize) -> bool,
        notes: &mut Vec<String>,
    ) -> (Vec<Attribute>, Vec<Option<TextColumnType>>) {
        if self.schema.is_some() {
            let types = self
                .columns
                .iter()
                .map(|(_, _, v)| match v {
                    Values::Typed(t, _) => Some(*t),
                    _ => None,
                })
                .collect();
            return (self.take_batch(), types);
        }
        let mut attributes = Vec::with_capacity(self.columns.len());
        let mut types = Vec::with_capacity(self.columns.len());
        for (i, (name, column, values)) in self.columns.into_iter().enumerate() {
            let Values::Learn(values) = values else {
                types.push(None);
                continue;
            };
            if skip(i) {
                types.push(None);
                continue;
            }
            match values.column_type() {
                Ok(t) => {
                    types.push(Some(t));
                    if self.keep
                        && let Ok(data) = values.finish()
                    {
                        attributes.push(Attribute { name, data });
                    }
                }
                Err((line, token)) => {
                    types.push(None);
                    notes.push(format!(
                        "{file}: column {column} ({name}) is not carried to the output: line \
                         {line} holds {}, not a number",
                        quoted(&token)
                    ));
                }
            }
        }
        (attributes, types)
    }
}

/// Whether columns 4–6 of a headerless file hold unit vectors on every row so far.
#[derive(Debug, Default)]
struct UnitCheck {
    /// The normals, if kept.
    normals: Vec<[f64; 3]>,
    keep: bool,
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
                    if self.keep {
                        self.normals.push([0.0; 3]);
                    }
                    return;
                }
                if (length - 1.0).abs() <= UNIT_TOLERANCE {
                    self.any_unit = true;
                    if self.keep {
                        self.normals.push(v);
                    }
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

/// Hands on the batch of a pass in batches: its points, the normals of columns 4–6 when the
/// first pass took them as such, and the attributes.
fn hand_on<E: From<ReadError>>(
    cloud: &mut CloudBuilder,
    check: Option<&mut UnitCheck>,
    attributes: &mut TextAttributes<'_>,
    pass: &mut Pass<'_, E>,
    file: &str,
    line: usize,
) -> Result<(), E> {
    let Pass::Batches {
        schema,
        sink,
        handed,
        ..
    } = pass
    else {
        return Ok(());
    };
    let fresh = CloudBuilder::new(cloud.normals.is_some(), 0);
    let mut batch = std::mem::replace(cloud, fresh).finish();
    if schema.normals {
        let normals = check.map(|c| std::mem::take(&mut c.normals));
        if normals.as_ref().map(Vec::len) != Some(batch.points.len()) {
            return Err(ReadError::Ascii {
                file: file.to_owned(),
                line,
                field: "columns 4-6".to_owned(),
                message: "no longer unit vectors on every row: the file changed since it was \
                          first read"
                    .to_owned(),
            }
            .into());
        }
        batch.normals = normals;
    }
    batch.attributes = attributes.take_batch();
    *handed = true;
    sink(batch)
}

/// Reads rows of columns (`.xyz`, `.txt`, `.pts`, `.asc`) and reports what it noticed. Columns are
/// separated by whitespace, or by commas or semicolons where the first row of values or
/// names is (CloudCompare's ASCII export writes either); every row takes that separator.
///
/// Blank lines and lines whose first non-blank character is `#` are ignored. A first data
/// row holding a single non-negative integer is the point-count line some scanners write at
/// the top of `.pts` files (and CloudCompare after its header): it is not a point, and the
/// rows after it must be as many as it states ([`ReadError::CountMismatch`]). The first
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
    let (cloud, schema) = xyz_pass(reader, name, options, slots, &mut Pass::Whole)?;
    Ok(ReadOutcome {
        cloud,
        notes: schema.notes,
    })
}

/// [`ReadError::CountMismatch`] where a point-count line `stated` (count, line) disagrees
/// with the `rows` read.
pub(crate) fn check_count(
    name: &str,
    stated: Option<(u64, usize)>,
    rows: u64,
) -> Result<(), ReadError> {
    match stated {
        Some((stated, line)) if stated != rows => Err(ReadError::CountMismatch {
            file: name.to_owned(),
            line,
            stated,
            found: rows,
        }),
        _ => Ok(()),
    }
}

/// One pass over a headerless text file ([`read_xyz_slots`]) as `pass` says: the cloud (empty
/// unless [`Pass::Whole`]) and what was learnt of its columns.
fn xyz_pass<E: From<ReadError>>(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
    slots: &[&str],
    pass: &mut Pass<'_, E>,
) -> Result<(PointCloud, TextSchema), E> {
    let mut lines = Lines::new(reader, 0);
    let mut roles: Vec<Role> = Vec::new();
    let mut first_row = true;
    let mut cloud = CloudBuilder::new(false, 0);
    let mut check: Option<UnitCheck> = None;
    let mut attributes = TextAttributes::new(pass);
    let schema_normals = pass.schema().map(|s| s.normals);
    let mut last_line = 0;
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
    // The point-count line, if the file has one, and the rows read.
    let mut stated: Option<(u64, usize)> = None;
    let mut rows: u64 = 0;
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
                stated = separator
                    .fields(text)
                    .next()
                    .and_then(|t| t.parse::<u64>().ok())
                    .map(|n| (n, line));
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
                }
                .into());
            }
            if found < 3 {
                return Err(ReadError::UnsupportedColumnCount {
                    file: name.to_owned(),
                    line,
                    found,
                }
                .into());
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
                        }
                        .into());
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
                        check = Some(UnitCheck {
                            // A whole read keeps them in case they are normals; a pass in
                            // batches, when the first pass found they are.
                            keep: schema_normals.unwrap_or(matches!(pass, Pass::Whole)),
                            ..UnitCheck::default()
                        });
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
            }
            .into());
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
                    attributes.push(i, name, line, token)?;
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
                Role::Attribute(i) => attributes.push(i, name, line, token)?,
                Role::Skip => {}
            }
        }
        if let Some(check) = &mut check {
            check.push(line, candidate);
        }
        last_line = line;
        rows += 1;
        match pass {
            Pass::Whole => cloud.push(values),
            Pass::Profile => {}
            Pass::Batches { max, .. } => {
                cloud.push(values);
                if cloud.points.len() as u64 >= *max {
                    hand_on(
                        &mut cloud,
                        check.as_mut(),
                        &mut attributes,
                        pass,
                        name,
                        line,
                    )?;
                }
            }
        }
    }
    check_count(name, stated, rows)?;
    if let Pass::Batches { handed, .. } = pass
        && (!*handed || !cloud.points.is_empty())
    {
        hand_on(
            &mut cloud,
            check.as_mut(),
            &mut attributes,
            pass,
            name,
            last_line,
        )?;
    }
    let mut cloud = cloud.finish();
    let mut notes = Vec::new();
    let width = roles.len();
    let mut normals_found = false;
    if options.columns.is_none() && named.is_none() && width > 3 {
        if let Some(check) = check {
            match check.failed {
                None if check.any_unit => {
                    if matches!(pass, Pass::Whole) {
                        cloud.normals = Some(check.normals);
                    }
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
    let (kept, columns) = attributes.finish(name, |i| normal_columns.contains(&i), &mut notes);
    if matches!(pass, Pass::Whole) {
        cloud.attributes = kept;
    }
    let schema = match pass.schema() {
        // The notes of the first pass, which learnt what this one reads.
        Some(schema) => schema.clone(),
        None => TextSchema {
            columns,
            normals: normals_found,
            notes,
            csv: false,
        },
    };
    Ok((cloud, schema))
}

/// The first pass over a text file (CSV if `csv`, else headerless XYZ) read in batches: what
/// its columns are, in constant memory.
pub(crate) fn profile(
    reader: impl BufRead,
    name: &str,
    csv: bool,
    options: &ReadOptions,
) -> Result<TextSchema, ReadError> {
    let pass = &mut Pass::<ReadError>::Profile;
    let (_, schema) = if csv {
        csv::csv_pass(reader, name, options, &SLOT_NAMES, pass)?
    } else {
        xyz_pass(reader, name, options, &SLOT_NAMES, pass)?
    };
    Ok(schema.with_csv(csv))
}

impl TextSchema {
    fn with_csv(mut self, csv: bool) -> Self {
        self.csv = csv;
        self
    }
}

/// Reads a text file as its first pass `schema` says, handing the rows to `sink` in clouds of
/// at most `max` points, with exactly the values a whole read gives; returns the first pass's
/// notes.
pub(crate) fn read_batches<E: From<ReadError>>(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
    schema: &TextSchema,
    max: u64,
    sink: &mut dyn FnMut(PointCloud) -> Result<(), E>,
) -> Result<Vec<String>, E> {
    let pass = &mut Pass::Batches {
        schema,
        max: max.max(1),
        sink,
        handed: false,
    };
    if schema.csv {
        csv::csv_pass(reader, name, options, &SLOT_NAMES, pass)?;
    } else {
        xyz_pass(reader, name, options, &SLOT_NAMES, pass)?;
    }
    Ok(schema.notes.clone())
}

mod csv;
pub(crate) use csv::read_csv_slots;
pub use csv::{read_csv, read_csv_with};
