//! `curvature` evaluates a large cloud in chunks and keeps only compact columns of each: the
//! rows must still be those of the library's evaluation of the whole cloud, in input order and
//! bit for bit (the text output prints the shortest decimal that reads back to the same bits).

use mls_core::{MlsConfig, MlsSurface, Parallelism, Point, UnitNormal, Vector};
use mls_shapes::{Torus, normals, points, random, surface_points};

use crate::common::{CURVATURE_HEADER, Table, mlscurv, run_ok, write_xyz};

/// More points than one chunk of the CLI (16,384), in random order, so that chunks are
/// scattered over the whole surface and their boundaries fall anywhere.
const POINTS: usize = 40_000;

/// Seed of the random torus samples.
const SEED: u64 = 5;

/// Gaussian scale: about 3 mean spacings of the random samples (the torus's area is
/// 4π² R r ≈ 11.8).
const H: f64 = 0.05;

#[test]
fn chunked_rows_equal_the_library_on_the_whole_cloud() {
    let samples = surface_points(&random(&Torus::new(1.0, 0.3), POINTS, SEED));
    let (p, n) = (points(&samples), normals(&samples));
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("torus.xyz");
    let out = dir.path().join("out.csv");
    write_xyz(&input, &p, Some(&n));
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args([
                "--method",
                "paper",
                "--normals",
                "file",
                "--h",
                &H.to_string(),
                "--quiet",
            ]),
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(table.header.join(","), CURVATURE_HEADER);
    assert_eq!(table.rows.len(), POINTS);

    let pts: Vec<Point> = p.iter().map(|&q| Point::from(q)).collect();
    // The command normalises file normals once when it reads them, and the surface again.
    let nrm: Vec<Vector> = n
        .iter()
        .map(|&v| UnitNormal::new(Vector::from(v)).unwrap().into_inner())
        .collect();
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(H)).unwrap();
    let expected = surface.curvature_at_points(&pts, Parallelism::Rayon);
    let status = table.col("status");
    for (i, (row, r)) in table.rows.iter().zip(&expected).enumerate() {
        assert_eq!(&row[..3], &p[i], "row {i}: position");
        let c = r
            .as_ref()
            .unwrap_or_else(|s| panic!("row {i}: library status {s:?}"));
        assert_eq!(row[status], 0.0, "row {i}: status");
        let c = &c.curvature;
        let want = [
            c.normal.x, c.normal.y, c.normal.z, c.k1, c.k2, c.mean, c.gauss, c.d1.x, c.d1.y,
            c.d1.z, c.d2.x, c.d2.y, c.d2.z,
        ];
        for (k, (got, want)) in row[3..16].iter().zip(want).enumerate() {
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "row {i}, column {}: {got:e} against the library's {want:e}",
                table.header[3 + k]
            );
        }
    }
}
