//! Times writing and reading a generated cloud of one million points, in a temporary
//! directory. Not a test: timings depend on the machine. Run it optimised:
//!
//! ```text
//! cargo run --release -p mls-io --example io_speed [points]
//! ```

use std::error::Error;
use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

use mls_io::{Column, PlyFormat, PointCloud, read_point_cloud, write_csv, write_ply};

/// Times `f`, printing the duration and the file size.
fn timed<T>(label: &str, path: &Path, f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let value = f();
    let elapsed = start.elapsed();
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    println!(
        "{label:<48} {:>8.3} s  {:>7.1} MB",
        elapsed.as_secs_f64(),
        size as f64 / 1e6
    );
    (value, elapsed)
}

fn main() -> Result<(), Box<dyn Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1_000_000);
    let dir = tempfile::tempdir()?;

    // Points on a unit sphere with outward normals, spread by a golden-angle spiral.
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    let normals: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            [r * t.cos(), r * t.sin(), z]
        })
        .collect();
    let cloud = PointCloud {
        points: normals.iter().map(|v| v.map(|c| 2.0 * c)).collect(),
        normals: Some(normals),
        ..PointCloud::default()
    };
    println!("{n} points");

    // The usual input: x y z nx ny nz as float32, written by hand like a scanner would.
    let f32_path = dir.path().join("input_f32.ply");
    timed(
        "write input PLY (6 x float32, hand-rolled)",
        &f32_path,
        || write_f32_ply(&f32_path, &cloud),
    )
    .0?;
    let (read, _) = timed("read input PLY (6 x float32)", &f32_path, || {
        read_point_cloud(&f32_path)
    });
    assert_eq!(read?.len(), n);

    // Points and normals as written by the tools: doubles.
    let f64_path = dir.path().join("cloud.ply");
    timed("write_ply points+normals (6 x double)", &f64_path, || {
        write_ply(&f64_path, &cloud.columns(), PlyFormat::BinaryLittleEndian)
    })
    .0?;
    let (read, _) = timed("read points+normals (6 x double)", &f64_path, || {
        read_point_cloud(&f64_path)
    });
    assert_eq!(read?, cloud);

    // The full curvature output: 16 doubles and an int status per point.
    let extra: Vec<Vec<f64>> = (0..10)
        .map(|k| (0..n).map(|i| (i * 10 + k) as f64 * 1e-3).collect())
        .collect();
    let status: Vec<i32> = (0..n).map(|i| (i % 8) as i32).collect();
    let names = [
        "k1", "k2", "mean", "gauss", "d1x", "d1y", "d1z", "d2x", "d2y", "d2z",
    ];
    let mut columns = cloud.columns();
    columns.extend(names.iter().zip(&extra).map(|(n, d)| Column::f64(n, d)));
    columns.push(Column::i32("status", &status));

    let table_path = dir.path().join("table.ply");
    timed("write_ply 17 columns (binary)", &table_path, || {
        write_ply(&table_path, &columns, PlyFormat::BinaryLittleEndian)
    })
    .0?;
    timed(
        "read 17-column PLY (11 columns as attributes)",
        &table_path,
        || read_point_cloud(&table_path),
    )
    .0?;
    // The same without the file system (no fsync, no page cache), to separate the costs.
    let start = Instant::now();
    mls_io::write_ply_to(
        std::io::sink(),
        "sink",
        &columns,
        PlyFormat::BinaryLittleEndian,
    )?;
    println!(
        "{:<48} {:>8.3} s",
        "write_ply_to 17 columns (binary, to io::sink)",
        start.elapsed().as_secs_f64()
    );
    let ascii_path = dir.path().join("table_ascii.ply");
    timed("write_ply 17 columns (ascii)", &ascii_path, || {
        write_ply(&ascii_path, &columns, PlyFormat::Ascii)
    })
    .0?;
    timed("read 17-column ascii PLY", &ascii_path, || {
        read_point_cloud(&ascii_path)
    })
    .0?;
    let laz_path = dir.path().join("table.laz");
    timed("write LAZ 17 columns (extra bytes)", &laz_path, || {
        mls_io::write_las(&laz_path, &columns, true)
    })
    .0?;
    let (read, _) = timed(
        "read 17-column LAZ (format 6 + extra bytes)",
        &laz_path,
        || read_point_cloud(&laz_path),
    );
    let read = read?;
    let las_path = dir.path().join("table.las");
    timed(
        "write LAS from LAZ input (all dimensions)",
        &las_path,
        || {
            mls_io::write_point_cloud_as_with(
                &las_path,
                mls_io::FileFormat::Las,
                &read.columns(),
                &mls_io::WriteOptions {
                    las: read.las.as_ref(),
                    ..mls_io::WriteOptions::default()
                },
            )
        },
    )
    .0?;
    timed("read that LAS", &las_path, || read_point_cloud(&las_path)).0?;
    let csv_path = dir.path().join("table.csv");
    timed("write_csv 17 columns", &csv_path, || {
        write_csv(&csv_path, &columns)
    })
    .0?;
    timed("read 17-column CSV", &csv_path, || {
        read_point_cloud(&csv_path)
    })
    .0?;
    Ok(())
}

/// Writes x y z nx ny nz as little-endian float32, the common scanner layout, which the
/// library itself never writes (it writes doubles).
fn write_f32_ply(path: &Path, cloud: &PointCloud) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nend_header\n",
        cloud.len()
    )?;
    let normals = cloud.normals.as_deref().unwrap_or_default();
    for (p, v) in cloud.points.iter().zip(normals) {
        for c in p.iter().chain(v) {
            out.write_all(&(*c as f32).to_le_bytes())?;
        }
    }
    out.flush()
}
