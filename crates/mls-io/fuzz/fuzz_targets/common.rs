//! Checks shared by the three reader targets: what every successful read and every error must
//! satisfy, whatever the input bytes.

use mls_io::{PointCloud, ReadError};

/// Every coordinate and normal component is finite, and there is one normal per point.
pub fn check_cloud(cloud: &PointCloud) {
    assert!(cloud.points.iter().flatten().all(|c| c.is_finite()));
    if let Some(normals) = &cloud.normals {
        assert_eq!(normals.len(), cloud.points.len());
        assert!(normals.iter().flatten().all(|c| c.is_finite()));
    }
}

/// The error message is one line that starts with the display name.
pub fn check_error(err: &ReadError, name: &str) {
    let message = err.to_string();
    assert!(!message.contains('\n'), "not one line: {message:?}");
    assert!(message.starts_with(name), "no file name: {message:?}");
}
