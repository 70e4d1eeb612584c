// Field output for ParaView and meshio: one VTK XML UnstructuredGrid file (.vtu) per output
// time and a ParaView collection (.pvd) that lists them as a time series.
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
  std::vector<std::pair<std::string, std::vector<double>>> cell_scalars;  // one per cell, in order
  std::vector<std::pair<std::string, std::vector<int>>> cell_ints;  // Int32 per cell (body id)
};

// The .vtu document (VTKFile version 0.1, every DataArray format="ascii", one Piece), in this
// layout, which VTK's XML reader and meshio's vtu reader both accept:
//   FieldData:  TimeValue (Float64)
//   Piece:      NumberOfPoints = n, NumberOfCells = quads + tris
//     PointData: point_vectors (Float64, 3 components), then point_scalars (Float64)
//     CellData:  cell_scalars (Float64), then cell_ints (Int32)
//     Points:    Float64, 3 components
//     Cells:     connectivity (Int32), offsets (Int64, end of each cell), types (UInt8)
// One tuple per line. Doubles are written by append_number (shortest round-trip form, so
// Float64 data read back bit for bit); non-finite values as "nan", "inf", "-inf" (see the note
// in vtu_writer.cpp: meshio reads them, VTK's own XML reader does not).
// Throws std::invalid_argument, naming the array, if an array name is empty, repeated within
// its section or contains a control character; if a point array has not n columns or entries or
// a cell array not one entry per cell; if a cell refers to a point outside [0, n); or if `time`
// is not finite.
std::string format_vtu(const VtuData& data);

// The .pvd collection: one <DataSet timestep="t" group="" part="0" file="f"/> per entry, in the
// given order. File names are written as given (ParaView resolves them relative to the .pvd).
// Throws std::invalid_argument if a time is not finite or a file name is empty or contains a
// control character.
std::string format_pvd(const std::vector<std::pair<double, std::string>>& time_and_relative_file);

}  // namespace ricochet
