// Field output for ParaView and meshio: one VTK XML UnstructuredGrid file (.vtu) per output
// time and a ParaView collection (.pvd) that lists them as a time series. 2D meshes (VtuData)
// and 3D ones (VtuData3) are written by the same code in the same layout and encodings.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace ricochet {

// One snapshot of the mesh and its fields. Units are the caller's (the harness uses SI).
struct VtuData {
  Eigen::Matrix2Xd points;                       // 2 x n coordinates [m]; written as x y 0
  std::vector<std::array<int, 4>> quads;         // point indices, VTK_QUAD (9)
  std::vector<std::array<int, 3>> tris;          // VTK_TRIANGLE (5); cells are quads, then tris
  double time = 0.0;                             // [s], FieldData "TimeValue" (Float64, 1 tuple)
  std::vector<std::pair<std::string, Eigen::Matrix2Xd>> point_vectors;  // 2 x n; z written as 0
  std::vector<std::pair<std::string, std::vector<double>>> point_scalars;  // n values
  std::vector<std::pair<std::string, std::vector<int>>> point_ints;  // Int32, n values
  std::vector<std::pair<std::string, std::vector<double>>> cell_scalars;  // one per cell, in order
  // Symmetric tensors, 6 values per cell in VTK order (XX, YY, ZZ, XY, YZ, XZ); written with
  // ComponentName0..5 = XX ... XZ.
  std::vector<std::pair<std::string, std::vector<double>>> cell_tensors;
  std::vector<std::pair<std::string, std::vector<int>>> cell_ints;  // Int32 per cell (body id)
};

// One snapshot of a 3D mesh and its fields: VtuData with 3D points and cells. The members and
// their checks are VtuData's; vectors have three components of their own.
struct VtuData3 {
  Eigen::Matrix3Xd points;                       // 3 x n coordinates [m]
  std::vector<std::array<int, 8>> hexes;         // VTK_HEXAHEDRON (12), corner order of mesh.hpp
  std::vector<std::array<int, 4>> tets;          // VTK_TETRA (10); cells are hexes, then tets
  double time = 0.0;                             // [s], FieldData "TimeValue"
  std::vector<std::pair<std::string, Eigen::Matrix3Xd>> point_vectors;  // 3 x n
  std::vector<std::pair<std::string, std::vector<double>>> point_scalars;  // n values
  std::vector<std::pair<std::string, std::vector<int>>> point_ints;  // Int32, n values
  std::vector<std::pair<std::string, std::vector<double>>> cell_scalars;  // one per cell, in order
  std::vector<std::pair<std::string, std::vector<double>>> cell_tensors;  // 6 per cell, VTK order
  std::vector<std::pair<std::string, std::vector<int>>> cell_ints;  // Int32 per cell
};

// How the DataArrays of the Piece are stored (docs/outputs.md; the case keys
// output.field_format and output.field_compression, docs/case-format.md).
enum class VtuEncoding {
  ascii,   // format="ascii": text, one tuple per line
  binary,  // format="appended" into <AppendedData encoding="raw">: the bytes themselves
  base64,  // format="binary": base64 text inside each DataArray (inline)
};
enum class VtuCompression { none, zlib };  // zlib: vtkZLibDataCompressor blocks (binary, base64)
struct VtuFormat {
  VtuEncoding encoding = VtuEncoding::ascii;
  VtuCompression compression = VtuCompression::none;  // must be none with ascii
};
// Uncompressed size of a zlib block [bytes] (the block size VTK's own writers use by default).
inline constexpr std::size_t kVtuZlibBlock = 32768;

// The .vtu document (one Piece), in this layout, which VTK's XML reader and meshio's vtu reader
// both accept:
//   FieldData:  TimeValue (Float64, always format="ascii": one number, shortest round-trip text)
//   Piece:      NumberOfPoints = n, NumberOfCells = quads + tris (3D: hexes + tets)
//     PointData: point_vectors (Float64, 3 components), point_scalars (Float64), point_ints (Int32)
//     CellData:  cell_scalars (Float64), cell_tensors (Float64, 6 components), cell_ints (Int32)
//     Points:    Float64, 3 components
//     Cells:     connectivity (Int32), offsets (Int64, end of each cell), types (UInt8)
// ascii: VTKFile version 0.1, one tuple per line (connectivity: one cell per line). Doubles are
// written by append_number (shortest round-trip form, so Float64 data read back bit for bit);
// non-finite values as "nan", "inf", "-inf" (see the note in vtu_writer.cpp: meshio reads them,
// VTK's own XML reader does not).
// binary, base64: VTKFile version 1.0, header_type="UInt64", byte_order of this machine, the
// values' own bytes. Each array's data is preceded by a header of UInt64 words:
//   uncompressed: [number of data bytes], then the data;
//   zlib (compressor="vtkZLibDataCompressor"): [number of blocks b, block size kVtuZlibBlock,
//     size of the last block if partial else 0, compressed size of each block (b words)], then
//     each block compressed by zlib's compress2 at level 1 (Z_BEST_SPEED: on the oblique plate's
//     fields the higher levels save about 1 % for 1.6 to 7.6 times the time), in order.
// binary: every array is <DataArray ... format="appended" offset="o"/>, o the byte offset of
// its header in the data after the '_' that opens <AppendedData encoding="raw">.
// base64: every array is <DataArray ... format="binary"> with base64 text (RFC 4648, padded):
// uncompressed, header and data encoded together; compressed, the header encoded, then the
// blocks encoded on their own (VTK's layout of both).
// Throws std::invalid_argument, naming the array, if an array name is empty, repeated within
// its section or contains a control character; if a point array has not n columns or entries or
// a cell array not one entry (tensors: 6) per cell; if a cell refers to a point outside [0, n);
// if `time` is not finite; or if `format` asks for zlib with ascii.
std::string format_vtu(const VtuData& data, const VtuFormat& format = {});
// The same document for a 3D mesh: points and point vectors as written, cells VTK_HEXAHEDRON
// (12, 8 corners) then VTK_TETRA (10, 4 corners), with the same checks.
std::string format_vtu(const VtuData3& data, const VtuFormat& format = {});

// The .pvd collection: one <DataSet timestep="t" group="" part="0" file="f"/> per entry, in the
// given order. File names are written as given (ParaView resolves them relative to the .pvd).
// Throws std::invalid_argument if a time is not finite or a file name is empty or contains a
// control character.
std::string format_pvd(const std::vector<std::pair<double, std::string>>& time_and_relative_file);

}  // namespace ricochet
