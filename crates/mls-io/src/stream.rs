//! A point-cloud file read in batches, as many times as needed: the batch source of a run
//! over a cloud larger than memory.
//!
//! [`PointStream::open`] learns what a pass needs before it starts: the number of points, the
//! bounding box, whether there are normals, the reader's notes, the LAS layout. LAS and LAZ
//! say all of it in their header (the box loosely); the other formats are read through once
//! for it, in constant memory: PLY and E57 for the box (and E57 for the count of valid
//! points), text for the box, the count and the columns' meaning and types, which depend on
//! every row ([`read_xyz_with`](crate::read_xyz_with)). Each [`PointStream::for_each_batch`]
//! then reads the file again from its start and hands its points on in file order, a bounded
//! number at a time, with exactly the values a whole read gives.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use crate::text::TextSchema;
use crate::{
    AttributeType, FileFormat, LasReader, LasTemplate, PointCloud, ReadError, ReadOptions,
    SLOT_NAMES,
};

/// Points per batch of the first pass over a file that is not LAS.
const PROFILE_BATCH: u64 = 1 << 16;

/// The most points of a batch of [`PointStream::for_each_batch`], whatever the caller asks:
/// tens of MB with the attributes, the size of a LAS batch ([`LasReader::batch_len`]). A
/// larger batch is no faster, and would cost memory beside the caller's own per point.
const MAX_BATCH: u64 = 1 << 18;

/// How a format is read again.
#[derive(Debug)]
enum Kind {
    Las,
    Ply,
    Text(Box<TextSchema>),
    E57,
}

/// A point-cloud file read in batches ([`PointStream::for_each_batch`]), as many times as
/// needed, in constant memory for every format: LAS/LAZ, PLY (ASCII or binary), XYZ and CSV
/// text, E57.
#[derive(Debug)]
pub struct PointStream {
    path: PathBuf,
    name: String,
    format: FileFormat,
    options: ReadOptions,
    kind: Kind,
    len: u64,
    has_normals: bool,
    notes: Vec<String>,
    template: Option<LasTemplate>,
    bounds: ([f64; 3], [f64; 3]),
    record_len: u64,
    scans_have_poses: bool,
    attributes: Vec<(String, AttributeType)>,
}

impl PointStream {
    /// Opens `path` as `format` with `options` (the column names of a text file), reading
    /// what a pass needs to know first (see the module's documentation).
    ///
    /// # Errors
    /// [`ReadError::IsADirectory`], [`ReadError::ColumnsForPly`] for column names given for
    /// a format that names its own, and every error a whole read of the file would give.
    pub fn open(path: &Path, format: FileFormat, options: &ReadOptions) -> Result<Self, ReadError> {
        let name = path.display().to_string();
        if path.is_dir() {
            return Err(ReadError::IsADirectory { file: name });
        }
        if options.columns.is_some() && !matches!(format, FileFormat::Xyz | FileFormat::Csv) {
            return Err(ReadError::ColumnsForPly { file: name });
        }
        let mut stream = Self {
            path: path.to_path_buf(),
            name,
            format,
            options: options.clone(),
            kind: Kind::Ply,
            len: 0,
            has_normals: false,
            notes: Vec::new(),
            template: None,
            bounds: ([0.0; 3], [0.0; 3]),
            record_len: 0,
            scans_have_poses: false,
            attributes: Vec::new(),
        };
        match format {
            FileFormat::Las | FileFormat::Laz => {
                let reader = LasReader::open(path)?;
                stream.kind = Kind::Las;
                stream.len = reader.len();
                stream.has_normals = reader.has_normals();
                stream.notes = reader.notes().to_vec();
                stream.template = Some(reader.template().clone());
                stream.bounds = reader.header_bounds();
                stream.record_len = reader.record_len() as u64;
                stream.attributes = columns(&reader.empty_cloud(0));
                return Ok(stream);
            }
            FileFormat::Ply => stream.kind = Kind::Ply,
            FileFormat::E57 => stream.kind = Kind::E57,
            FileFormat::Xyz | FileFormat::Csv => {
                let schema = crate::text::profile(
                    stream.open_file()?,
                    &stream.name,
                    format == FileFormat::Csv,
                    options,
                )?;
                stream.kind = Kind::Text(Box::new(schema));
            }
        }
        // The first pass: count, box, normals, record size.
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut record = 0;
        let (mut len, mut normals, mut poses) = (0, false, false);
        let mut attributes = Vec::new();
        let notes = stream.read(PROFILE_BATCH, &mut |cloud: PointCloud| {
            for p in &cloud.points {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            len += cloud.points.len() as u64;
            normals = cloud.normals.is_some();
            attributes = columns(&cloud);
            poses = cloud
                .scans
                .as_ref()
                .is_some_and(|s| s.origins.iter().all(Option::is_some));
            record = 24
                + if normals { 24 } else { 0 }
                + cloud
                    .attributes
                    .iter()
                    .map(|a| a.data.ty().size() as u64)
                    .sum::<u64>();
            Ok::<(), ReadError>(())
        })?;
        if len == 0 {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        stream.len = len;
        stream.has_normals = normals;
        stream.notes = notes;
        stream.bounds = (lo, hi);
        stream.record_len = record;
        stream.scans_have_poses = poses;
        stream.attributes = attributes;
        Ok(stream)
    }

    fn open_file(&self) -> Result<BufReader<File>, ReadError> {
        let file = File::open(&self.path).map_err(|error| ReadError::Io {
            file: self.name.clone(),
            error,
        })?;
        Ok(BufReader::with_capacity(1 << 20, file))
    }

    /// One pass in batches of at most `max` points (not LAS); returns the notes.
    fn read<E: From<ReadError>>(
        &self,
        max: u64,
        sink: &mut dyn FnMut(PointCloud) -> Result<(), E>,
    ) -> Result<Vec<String>, E> {
        let reader = self.open_file()?;
        match &self.kind {
            Kind::Las => Ok(Vec::new()),
            Kind::Ply => {
                let size = reader.get_ref().metadata().ok().map(|m| m.len());
                crate::ply::read_batches(reader, &self.name, size, &SLOT_NAMES, max, sink)
            }
            Kind::E57 => crate::e57::read_batches(reader, &self.name, max, sink),
            Kind::Text(schema) => {
                crate::text::read_batches(reader, &self.name, &self.options, schema, max, sink)
            }
        }
    }

    /// The file's name, as errors give it.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The format it is read as.
    pub fn format(&self) -> FileFormat {
        self.format
    }

    /// The number of points: the header's for LAS/LAZ and PLY, those read for text and E57
    /// (E57's valid points).
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the points have normals.
    pub fn has_normals(&self) -> bool {
        self.has_normals
    }

    /// What the reader noticed, as the whole-file readers report it.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The layout of a LAS/LAZ file.
    pub fn las_template(&self) -> Option<&LasTemplate> {
        self.template.as_ref()
    }

    /// A box holding every point (minimum, maximum): the header's for LAS/LAZ, which writers
    /// keep loosely; measured, so exact, for the other formats.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.bounds
    }

    /// The name and type of every attribute, in the order of each batch's.
    pub fn attributes(&self) -> &[(String, AttributeType)] {
        &self.attributes
    }

    /// Whether the file is E57 and every scan has a pose: then every batch's
    /// [`PointCloud::scans`] gives each point's scanner position
    /// ([`Scans::viewpoints`](crate::Scans::viewpoints)).
    pub fn scans_have_poses(&self) -> bool {
        self.scans_have_poses
    }

    /// Bytes a point takes once read: its record for LAS/LAZ; coordinates, normals and
    /// attributes in their types for the other formats.
    pub fn record_len(&self) -> u64 {
        self.record_len
    }

    /// Reads every point from the start of the file in batches of at most `max` points (and
    /// at most 2^18, or a LAS file's [`LasReader::batch_len`]), calling `f` with each batch's
    /// first index and cloud (its attributes left out unless
    /// `with_attributes`): the same points, normals and attributes, in the same order, as a
    /// whole read gives.
    ///
    /// # Errors
    /// Those of the reader, [`ReadError::Changed`] when the file no longer holds
    /// [`Self::len`] points, and `f`'s.
    pub fn for_each_batch<E: From<ReadError>>(
        &self,
        with_attributes: bool,
        max: u64,
        mut f: impl FnMut(u64, PointCloud) -> Result<(), E>,
    ) -> Result<(), E> {
        let max = max.max(1);
        let mut first = 0u64;
        if let Kind::Las = self.kind {
            let mut reader = LasReader::open(&self.path)?;
            // Several LAZ chunks per thread, about 30 MB of points and attributes, unless
            // the caller keeps more per point than that.
            let batch = reader.batch_len().min(max).max(1);
            loop {
                let mut chunk = reader.empty_cloud(batch as usize);
                if !with_attributes {
                    // Nothing to decode them into: they are skipped.
                    chunk.attributes.clear();
                }
                let n = reader.read_into(&mut chunk, batch)?;
                if n == 0 {
                    break;
                }
                f(first, chunk)?;
                first += n as u64;
            }
        } else {
            self.read(max.min(MAX_BATCH), &mut |mut cloud: PointCloud| {
                if !with_attributes {
                    cloud.attributes.clear();
                }
                let n = cloud.points.len() as u64;
                if n > 0 {
                    f(first, cloud)?;
                }
                first += n;
                Ok::<(), E>(())
            })?;
        }
        if first != self.len {
            return Err(ReadError::Changed {
                file: self.name.clone(),
                first: self.len,
                now: first,
            }
            .into());
        }
        Ok(())
    }
}

/// The name and type of each of a cloud's attributes.
fn columns(cloud: &PointCloud) -> Vec<(String, AttributeType)> {
    cloud
        .attributes
        .iter()
        .map(|a| (a.name.clone(), a.data.ty()))
        .collect()
}
