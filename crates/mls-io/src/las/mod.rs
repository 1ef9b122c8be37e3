//! LAS and LAZ (ASPRS LAS 1.0–1.4, LASzip-compressed or not) through the `las` crate.
//!
//! Reading gives the points as `f64` world coordinates (the crate applies the header's scale
//! and offset), every standard dimension of the point format and every extra-bytes attribute
//! as [`Attribute`](crate::Attribute)s in their stored types (`dims.rs` names them), normals
//! from `f64` extra bytes `nx`, `ny`, `nz` (as `mlscurv` writes them), and the header's layout
//! as a [`LasTemplate`].
//!
//! Writing is LAS 1.4: point format 6 without a template, `x y z` in the records, columns
//! named as a standard dimension of the format and of its type (a flag only if every value
//! fits its bits) in that field, and every other column as a named extra-bytes attribute of
//! its type (`f64` for float columns, `i32` for integer ones), described by an Extra Bytes
//! VLR so that PDAL, laspy and CloudCompare show them as dimensions. With the template of a
//! LAS input: its point format (without waveform packets), scale, offset, GPS time type, file
//! source id and coordinate-system records, so its dimensions go back into their fields, and
//! its extra-bytes attributes keep their descriptors (options, scale, no-data value,
//! description).
//!
//! Without a template the coordinate scale is the power of ten `10^(floor(log10 E) - 7)`,
//! where `E` is the largest extent of the bounding box, and the offset is the box's minimum:
//! every coordinate is then stored within half a scale step, between 5e-9 and 5e-8 of `E`,
//! far below the 1e-6 relative resolution the curvature needs, and the stored integers stay
//! below 10^8, well inside the `i32` range. A decimal scale is what LiDAR tools expect to
//! display.

mod dims;
mod extra;
mod read;
mod write;

use las::{GpsTimeType, Vlr};

pub use read::LasReader;
pub(crate) use read::{read, read_stream};
pub use write::{LasSink, creation_date};
pub(crate) use write::{write_file, write_file_chunks, write_stream};

/// Points handed to the `las` reader or writer per call, for a LAZ file whose chunks hold
/// `chunk` points (`None`: uncompressed, or chunks of varying size). The codec works on whole
/// chunks, one per rayon thread, so a batch of a whole number of chunks per thread keeps every
/// thread busy to the end of the batch; about 2^18 points bounds the memory a header that
/// claims too many points can cost.
fn batch_points(chunk: Option<u32>) -> usize {
    const TARGET: usize = 1 << 18;
    let Some(chunk) = chunk.map(|c| c as usize).filter(|&c| c > 0) else {
        return TARGET;
    };
    let threads = rayon::current_num_threads().max(1);
    let chunks = TARGET.div_ceil(chunk);
    if chunk.saturating_mul(threads) > 4 * TARGET {
        // Chunks so large that one per thread would cost more than the bound: the codec
        // keeps the rest of a chunk for the next call.
        return (chunk * chunks).min(4 * TARGET);
    }
    chunk * chunks.next_multiple_of(threads)
}

/// The layout of a LAS input, kept so that LAS output from it looks like it: see
/// [`WriteOptions::las`](crate::WriteOptions::las).
#[derive(Clone, Debug, PartialEq)]
pub struct LasTemplate {
    /// The point format written: the input's, without waveform packets (4 → 1, 5 → 3,
    /// 9 → 6, 10 → 8).
    pub point_format: u8,
    /// The input's coordinate scale, x y z.
    pub scale: [f64; 3],
    /// The input's coordinate offset, x y z.
    pub offset: [f64; 3],
    gps_time_type: GpsTimeType,
    file_source_id: u16,
    has_wkt_crs: bool,
    /// The extra-bytes descriptors of the carried extra-bytes attributes, by name.
    descriptors: Vec<(String, extra::Descriptor)>,
    /// Records carried as they are (coordinate system and the like), not those that describe
    /// the input's own layout (extra bytes, LASzip, waveform packets, COPC).
    vlrs: Vec<Vlr>,
    evlrs: Vec<Vlr>,
}

impl LasTemplate {
    /// The layout [`write_las`](crate::write_las) chooses for a table without a template
    /// whose coordinates span the box `min`–`max` (finite): point format 6, the box's minimum
    /// as offset and the scale of its largest extent (see the module's documentation). For
    /// writing such a table in chunks ([`write_point_cloud_chunks`](crate::write_point_cloud_chunks)),
    /// whose box is known before its rows.
    pub fn fitted(min: [f64; 3], max: [f64; 3]) -> Self {
        let extent = (0..3).map(|i| max[i] - min[i]).fold(0.0, f64::max);
        let scale = write::coordinate_scale(extent);
        let builder = las::Builder::from(las::Version::new(1, 4));
        Self {
            point_format: 6,
            scale: [scale; 3],
            offset: min,
            gps_time_type: builder.gps_time_type,
            file_source_id: builder.file_source_id,
            has_wkt_crs: builder.has_wkt_crs,
            descriptors: Vec::new(),
            vlrs: Vec::new(),
            evlrs: Vec::new(),
        }
    }

    fn from_header(
        header: &las::Header,
        point_format: u8,
        descriptors: Vec<(String, extra::Descriptor)>,
    ) -> Self {
        let t = header.transforms();
        let carried = |v: &&Vlr| {
            let layout = (v.user_id == extra::USER_ID
                && (v.record_id == extra::RECORD_ID || (100..=354).contains(&v.record_id)))
                || v.user_id == "laszip encoded"
                || v.user_id == "copc";
            !layout
        };
        Self {
            point_format: dims::without_waveform(point_format),
            scale: [t.x.scale, t.y.scale, t.z.scale],
            offset: [t.x.offset, t.y.offset, t.z.offset],
            gps_time_type: header.gps_time_type(),
            file_source_id: header.file_source_id(),
            has_wkt_crs: header.has_wkt_crs(),
            descriptors,
            vlrs: header.vlrs().iter().filter(carried).cloned().collect(),
            evlrs: header.evlrs().iter().filter(carried).cloned().collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::batch_points;

    /// A batch is a whole number of chunks per thread, near 2^18 points, and bounded for
    /// huge chunks.
    #[test]
    fn batches_are_whole_chunks_per_thread() {
        let threads = rayon::current_num_threads();
        for chunk in [1, 1_000, 50_000, 100_000, 1 << 18] {
            let batch = batch_points(Some(chunk));
            let chunk = chunk as usize;
            if chunk * threads <= 4 << 18 {
                assert_eq!(batch % (chunk * threads), 0, "chunk {chunk}");
                assert!(batch >= 1 << 18 && batch < (1 << 18) + 2 * chunk * threads);
            } else {
                assert!(((1 << 18)..=(4 << 18)).contains(&batch), "chunk {chunk}");
            }
        }
        assert_eq!(batch_points(Some(10_000_000)), 4 << 18);
        assert_eq!(batch_points(None), 1 << 18);
        assert_eq!(batch_points(Some(0)), 1 << 18);
    }
}
