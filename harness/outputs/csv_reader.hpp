// Reading CSV tables (RFC 4180), e.g. the DIR/summary.csv of `ricochet sweep`, for the gate
// checks (gates.hpp). Every error is an InputError "FILE:LINE: what is wrong".
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ricochet {

// A table of text cells: the header line's column names, then one row per record, each with
// exactly as many fields as the header. Cells are kept as text (empty = missing value);
// parse_csv_number() reads the numeric ones.
struct CsvTable {
  std::string file;                            // as given, for messages
  std::vector<std::string> columns;            // header, in file order
  std::vector<std::vector<std::string>> rows;  // rows[r][c], c indexes `columns`
  std::vector<long> lines;                     // line (1-based) on which row r starts

  // Index of the first column named `name` (a name may repeat; the first one wins).
  std::optional<std::size_t> column_index(std::string_view name) const;
  bool has_column(std::string_view name) const { return column_index(name).has_value(); }
  // The cell of row `row` in the first column named `name`; nullptr if there is no such column.
  const std::string* find(std::size_t row, std::string_view name) const;
  // Same, but throws InputError "FILE: no column 'NAME'; columns: ..." if there is none.
  const std::string& at(std::size_t row, std::string_view name) const;
  // The columns as one comma-separated list, for messages.
  std::string column_list() const;
};

// Parses CSV text per RFC 4180:
// - records end in LF or CRLF (a lone CR also ends a record); the last line break is optional;
// - fields are separated by ','; a field may be wrapped in double quotes, and then may hold
//   commas, line breaks and doubled quotes ("" stands for one "); nothing may follow the
//   closing quote except ',' or the end of the record;
// - a '"' inside an unquoted field is an error;
// - the first record is the header: at least one column, no empty name; names may repeat;
// - every other record must have as many fields as the header;
// - completely empty lines are skipped; a UTF-8 byte-order mark at the start is skipped.
// `file` names the source in messages, e.g. "out/summary.csv:7: row has 3 fields; the header
// has 4 columns".
CsvTable parse_csv(std::string_view text, const std::string& file);

// Reads and parses a file; InputError "FILE: cannot read: REASON" if it cannot be read.
CsvTable read_csv(const std::filesystem::path& path);

// A cell as a number: plain decimal or exponent notation ("0.000001", "1e-06", "-3", "+2.5"),
// also "nan", "inf", "-inf" as append_number writes them; leading and trailing spaces or tabs
// are ignored. nullopt if the text is empty or not entirely a number.
std::optional<double> parse_csv_number(std::string_view text);

}  // namespace ricochet
