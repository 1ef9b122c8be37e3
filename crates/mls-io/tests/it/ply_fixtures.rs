//! Hand-written PLY files with known contents.

use mls_io::read_ply;

use crate::{Body, ply};

#[test]
fn ascii_with_extra_properties_and_faces_after_vertices() {
    let file = b"\
ply \t
format ascii 1.0
comment made by hand, caf\xE9 in Latin-1
obj_info scanner 1
element vertex 3
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
property list uchar int flags
element face 1
property list uchar int vertex_indices
end_header
0 1 2 255 0 0 2 7 8
1.5 -2 3e2 0 255 0 0

-0.5 0.25 1 0 0 255 1 9
3 0 1 2
";
    let cloud = read_ply(&file[..], "hand.ply").unwrap();
    assert_eq!(
        cloud.points,
        [[0.0, 1.0, 2.0], [1.5, -2.0, 300.0], [-0.5, 0.25, 1.0]]
    );
    assert_eq!(cloud.normals, None);
}

#[test]
fn ascii_with_element_before_vertices_and_normals() {
    let file = "\
ply\r
format ascii 1.0\r
element camera 2\r
property float view_x\r
property list uchar float params\r
element vertex 2\r
property double nx\r
property double x\r
property double ny\r
property double y\r
property double nz\r
property double z\r
end_header\r
1 3 0.5 0.5 0.5\r
2 0\r
0 1 0 2 1 3\r
0.1 -1 0.2 -2 0.3 -3\r
";
    let cloud = read_ply(file.as_bytes(), "cam.ply").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [-1.0, -2.0, -3.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [0.1, 0.2, 0.3]]));
}

/// Mixed float32/float64 coordinates, a colour, a list inside the vertex element, an
/// element with a list before the vertices and faces after them.
fn mixed_binary(big: bool) -> Vec<u8> {
    let format = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let header = format!(
        "ply
format {format} 1.0
comment two elements around the vertices
element material 2
property uchar kind
property list uchar uint16 ids
element vertex 2
property float x
property double y
property uchar red
property float32 z
property list int8 float64 extra
property float64 nx
property float ny
property double nz
element face 1
property list uchar int vertex_indices
end_header
"
    );
    let mut body = Body {
        big,
        ..Body::default()
    };
    body.u8(1).u8(2).u16(10).u16(11);
    body.u8(2).u8(0);
    body.f32(0.5).f64(0.1).u8(200).f32(-3.25).i8(1).f64(9.0);
    body.f64(0.6).f32(0.0).f64(0.8);
    body.f32(1e30).f64(-1e-300).u8(0).f32(7.0).i8(0);
    body.f64(-1.0).f32(0.25).f64(1.0 / 3.0);
    body.u8(3).i32(0).i32(1).i32(0);
    ply(&header, &body.bytes)
}

#[test]
fn binary_mixed_types_both_byte_orders() {
    for big in [false, true] {
        let cloud = read_ply(&mixed_binary(big)[..], "mixed.ply").unwrap();
        assert_eq!(
            cloud.points,
            [[0.5, 0.1, -3.25], [f64::from(1e30_f32), -1e-300, 7.0]]
        );
        assert_eq!(
            cloud.normals,
            Some(vec![[0.6, 0.0, 0.8], [-1.0, 0.25, 1.0 / 3.0]])
        );
    }
}

#[test]
fn binary_fixed_size_vertices_after_fixed_size_element() {
    for big in [false, true] {
        let format = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let header = format!(
            "ply\nformat {format} 1.0\nelement pad 3\nproperty double w\nproperty short s\n\
             element vertex 2\nproperty int x\nproperty short y\nproperty char z\n\
             property ushort q\nproperty uint32 u\nend_header\n"
        );
        let mut body = Body {
            big,
            ..Body::default()
        };
        for _ in 0..3 {
            body.f64(f64::NAN).i16(-1);
        }
        body.i32(-100_000)
            .i16(-7)
            .i8(-128)
            .u16(65535)
            .u32(4_000_000_000);
        body.i32(1).i16(2).i8(3).u16(0).u32(0);
        let cloud = read_ply(&ply(&header, &body.bytes)[..], "ints.ply").unwrap();
        // NaN in a skipped property is not looked at.
        assert_eq!(cloud.points, [[-100_000.0, -7.0, -128.0], [1.0, 2.0, 3.0]]);
        assert_eq!(cloud.normals, None);
    }
}

#[test]
fn empty_vertex_element_is_an_empty_cloud() {
    let file = "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n\
                property float y\nproperty float z\nend_header\n";
    let cloud = read_ply(file.as_bytes(), "empty.ply").unwrap();
    assert!(cloud.is_empty());
}

#[test]
fn zero_length_normals_are_returned_as_read() {
    let file = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                end_header\n1 2 3 0 0 0\n";
    let cloud = read_ply(file.as_bytes(), "zero.ply").unwrap();
    assert_eq!(cloud.normals, Some(vec![[0.0; 3]]));
}

#[test]
fn pcl_normal_names_are_normals_unless_nx_is_there_too() {
    let header = |props: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
             property float z\n{props}end_header\n"
        )
    };
    let pcl = "property float normal_x\nproperty float normal_y\nproperty float normal_z\n\
               property float curvature\n";
    let file = header(pcl) + "1 2 3 0 1 0 0.5\n";
    let cloud = read_ply(file.as_bytes(), "pcl.ply").unwrap();
    assert_eq!(cloud.normals, Some(vec![[0.0, 1.0, 0.0]]));
    assert_eq!(cloud.attributes.len(), 1);
    let both = "property float nx\nproperty float ny\nproperty float nz\n\
                property float normal_x\nproperty float normal_y\nproperty float normal_z\n";
    let file = header(both) + "1 2 3 0 0 1 1 0 0\n";
    let cloud = read_ply(file.as_bytes(), "both.ply").unwrap();
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]));
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["normal_x", "normal_y", "normal_z"]);
}
