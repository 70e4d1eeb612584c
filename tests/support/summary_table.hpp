// A sweep's summary.csv in the tests, read with the harness's own reader (parse_csv,
// harness/outputs/csv_reader.hpp: RFC 4180, every row as wide as the header, or an InputError):
// its header, and its rows as column -> cell text, found by index, by column or by run id.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "harness/outputs/csv_reader.hpp"

namespace ricochet::test_support {

struct SummaryTable {
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;

  // The row whose run_id is `id`; std::logic_error if there is none.
  const std::map<std::string, std::string>& row(const std::string& id) const {
    for (const auto& r : rows)
      if (r.at("run_id") == id) return r;
    throw std::logic_error("no row " + id);
  }
  // The cell of row `r` in column `column`; std::out_of_range if either is missing.
  const std::string& cell(std::size_t r, const std::string& column) const { return rows.at(r).at(column); }
  // The run_id column, in row order.
  std::vector<std::string> ids() const {
    std::vector<std::string> v;
    for (const auto& r : rows) v.push_back(r.at("run_id"));
    return v;
  }
};

// The columns that differ between two runs of the same case: the machine's measurements
// (timings, memory, the implicit scheme's phase times) and when the summary was written.
inline bool is_measurement_column(const std::string& column) {
  static const std::set<std::string> measured = {"wall_seconds", "cpu_seconds", "element_steps_per_second",
                                                 "wall_seconds_min", "wall_seconds_max", "written_at",
                                                 "peak_memory_bytes"};
  return measured.count(column) > 0 || column.rfind("implicit.phase_seconds.", 0) == 0;
}

inline SummaryTable read_summary_table(const std::filesystem::path& path) {
  const CsvTable csv = read_csv(path);
  SummaryTable t;
  t.header = csv.columns;
  for (const auto& cells : csv.rows) {
    std::map<std::string, std::string> r;
    for (std::size_t c = 0; c < cells.size(); ++c) r.emplace(csv.columns[c], cells[c]);
    t.rows.push_back(std::move(r));
  }
  return t;
}

// The records of CSV text as the harness reads them (parse_csv): the header, then each row.
inline std::vector<std::vector<std::string>> csv_records(std::string_view text) {
  const CsvTable csv = parse_csv(text, "csv text");
  std::vector<std::vector<std::string>> out{csv.columns};
  out.insert(out.end(), csv.rows.begin(), csv.rows.end());
  return out;
}

}  // namespace ricochet::test_support
