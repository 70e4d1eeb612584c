// CSV text for time histories and sweep tables, and the number format shared by every text
// output of the harness (CSV, VTU, PVD; JSON uses it for finite values).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ricochet {

// Appends `value` in the shortest form that parses back (std::strtod) to the same double
// (std::to_chars without a format), e.g. "0.1", "1e-300", "-0", "1.7976931348623157e+308".
// Non-finite values are written as "nan" (any sign or payload), "inf" or "-inf".
void append_number(std::string& out, double value);

// One CSV field (RFC 4180): `text` unchanged unless it contains a comma, a double quote, CR or
// LF; then it is wrapped in double quotes with each inner double quote doubled.
std::string csv_field(std::string_view text);

// A numeric table: a header line of column names (each passed through csv_field), then one line
// per row of `rows_row_major` (row r is elements [r*k, (r+1)*k) for k columns), fields separated
// by ',' and numbers written by append_number. Lines end in '\n' (not CRLF); the last line too.
// Throws std::invalid_argument if there are no columns or the data size is not a multiple of
// the column count.
std::string format_csv(const std::vector<std::string>& columns,
                       const std::vector<double>& rows_row_major);

}  // namespace ricochet
