"""weights_tools.ply: the mesh reader (vertices and triangles) on ascii and binary files of
either endianness, with extra properties, and its errors naming the file."""
import struct

import numpy as np
import pytest

from weights_tools.ply import read_ply, read_ply_triangles

# A tetrahedron with one extra vertex property and, in the binary files, a face property after the list.
V = np.array([[0, 0, 0], [10, 0, 0], [0, 8, 0], [0, 0, 6]], dtype=np.float64)
T = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _head(fmt, face_props):
    return (f"ply\nformat {fmt} 1.0\ncomment made by a test\nelement vertex 4\nproperty float x\nproperty float y\n"
            f"property float z\nproperty uchar red\nelement face 4\n{face_props}end_header\n").encode("ascii")


def test_ascii_and_binary_meshes_read_alike(tmp_path):
    a = tmp_path / "a.ply"
    rows = "".join(f"{x:g} {y:g} {z:g} 7\n" for x, y, z in V) + "".join(f"3 {i} {j} {k}\n" for i, j, k in T)
    a.write_bytes(_head("ascii", "property list uchar int vertex_indices\n") + rows.encode("ascii"))
    for endian, fmt in (("<", "binary_little_endian"), (">", "binary_big_endian")):
        b = tmp_path / f"b{endian == '<'}.ply"
        body = b"".join(struct.pack(endian + "3fB", *v, 7) for v in V)
        body += b"".join(struct.pack(endian + "B3If", 3, *t, 0.5) for t in T)
        b.write_bytes(_head(fmt, "property list uchar uint vertex_indices\nproperty float quality\n") + body)
        Vb, Tb = read_ply_triangles(str(b))
        assert np.array_equal(Vb, V) and np.array_equal(Tb, T), fmt
    Va, Ta = read_ply_triangles(str(a))
    assert np.array_equal(Va, V) and np.array_equal(Ta, T) and Ta.dtype == np.int64
    assert np.array_equal(read_ply(str(a)), V.astype(np.float32))  # the cloud reader skips the faces alike


@pytest.mark.parametrize("faces, message", [
    ("4 0 1 2 3\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "faces must be triangles"),
    ("3 0 2 9\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "out of range"),
])
def test_bad_meshes_are_errors_naming_the_file(tmp_path, faces, message):
    p = tmp_path / "bad.ply"
    rows = "".join(f"{x:g} {y:g} {z:g} 7\n" for x, y, z in V) + faces
    p.write_bytes(_head("ascii", "property list uchar int vertex_indices\n") + rows.encode("ascii"))
    with pytest.raises(ValueError, match=message) as e:
        read_ply_triangles(str(p))
    assert str(p) in str(e.value)


def test_a_cloud_is_not_a_mesh(tmp_path):
    p = tmp_path / "cloud.ply"
    p.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                  b"end_header\n1 2 3\n")
    with pytest.raises(ValueError, match="needs a vertex and a face element"):
        read_ply_triangles(str(p))


def test_a_binary_quad_is_an_error_too(tmp_path):
    p = tmp_path / "quad.ply"
    body = b"".join(struct.pack("<3fB", *v, 7) for v in V)
    body += struct.pack("<B4I", 4, 0, 1, 2, 3) + b"".join(struct.pack("<B3I", 3, *t) for t in T[1:])
    p.write_bytes(_head("binary_little_endian", "property list uchar uint vertex_indices\n") + body)
    with pytest.raises(ValueError, match="faces must be triangles"):
        read_ply_triangles(str(p))


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_data_that_ends_early_or_is_not_a_ply_is_an_error_naming_the_file(tmp_path, fmt):
    p = tmp_path / "short.ply"
    if fmt == "ascii":
        body = "".join(f"{x:g} {y:g} {z:g} 7\n" for x, y, z in V).encode("ascii") + b"3 0 2 1\n3 0 1"
    else:
        body = b"".join(struct.pack("<3fB", *v, 7) for v in V) + struct.pack("<B3I", 3, 0, 2, 1) + b"\x03\x00"
    p.write_bytes(_head(fmt, "property list uchar uint vertex_indices\n") + body)
    with pytest.raises(ValueError, match="ends before") as e:
        read_ply_triangles(str(p))
    assert str(p) in str(e.value)
    q = tmp_path / "not.ply"
    q.write_bytes(b"solid cube\n")
    with pytest.raises(ValueError, match="not a PLY file") as e:
        read_ply_triangles(str(q))
    assert str(q) in str(e.value)
