#include "harness/outputs/csv_reader.hpp"

#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

[[noreturn]] void fail_at(const std::string& file, long line, const std::string& what) {
  throw InputError(file + ":" + std::to_string(line) + ": " + what);
}

std::string field_name(std::size_t index, const std::vector<std::string>& header) {
  std::string s = "field " + std::to_string(index + 1);
  if (index < header.size()) s += " (column '" + header[index] + "')";
  return s;
}

}  // namespace

std::optional<std::size_t> CsvTable::column_index(std::string_view name) const {
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) return c;
  return std::nullopt;
}

const std::string* CsvTable::find(std::size_t row, std::string_view name) const {
  const auto c = column_index(name);
  if (!c || row >= rows.size()) return nullptr;
  return &rows[row][*c];
}

const std::string& CsvTable::at(std::size_t row, std::string_view name) const {
  const auto c = column_index(name);
  if (!c) throw InputError(file + ": no column '" + std::string(name) + "'; columns: " + column_list());
  if (row >= rows.size())
    throw InputError(file + ": no row " + std::to_string(row) + " (" + std::to_string(rows.size()) + " rows)");
  return rows[row][*c];
}

std::string CsvTable::column_list() const {
  std::string s;
  for (const auto& c : columns) s += (s.empty() ? "" : ", ") + c;
  return s;
}

CsvTable parse_csv(std::string_view text, const std::string& file) {
  CsvTable t;
  t.file = file;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);

  long line = 1;               // current line
  std::size_t i = 0;
  const std::size_t n = text.size();
  bool have_header = false;

  // Consumes a line break at i (LF, CRLF or CR); true if there was one.
  auto take_newline = [&]() {
    if (i < n && text[i] == '\r') {
      ++i;
      if (i < n && text[i] == '\n') ++i;
      ++line;
      return true;
    }
    if (i < n && text[i] == '\n') {
      ++i;
      ++line;
      return true;
    }
    return false;
  };

  while (i < n) {
    if (take_newline()) continue;  // an empty line
    const long record_line = line;
    std::vector<std::string> fields;
    const std::vector<std::string>& header = have_header ? t.columns : fields;
    while (true) {  // one field per pass
      std::string field;
      if (i < n && text[i] == '"') {
        const long quote_line = line;
        ++i;
        while (true) {
          if (i >= n)
            fail_at(file, quote_line,
                    "unterminated quoted " + field_name(fields.size(), header) + ": no closing '\"'");
          const char c = text[i];
          if (c == '"') {
            if (i + 1 < n && text[i + 1] == '"') {
              field += '"';
              i += 2;
              continue;
            }
            ++i;
            break;
          }
          if (c == '\n' || (c == '\r' && !(i + 1 < n && text[i + 1] == '\n'))) ++line;
          field += c;
          ++i;
        }
        if (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r')
          fail_at(file, line,
                  "text after the closing quote of " + field_name(fields.size(), header) +
                      "; a quoted field must be followed by ',' or the end of the line");
      } else {
        while (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
          if (text[i] == '"')
            fail_at(file, line,
                    "'\"' inside unquoted " + field_name(fields.size(), header) +
                        "; quote the whole field and double the inner quotes (RFC 4180)");
          field += text[i++];
        }
      }
      fields.push_back(std::move(field));
      if (i < n && text[i] == ',') {
        ++i;
        continue;
      }
      take_newline();
      break;
    }

    if (!have_header) {
      for (std::size_t c = 0; c < fields.size(); ++c)
        if (fields[c].empty())
          fail_at(file, record_line, "header: column " + std::to_string(c + 1) + " has an empty name");
      t.columns = std::move(fields);
      have_header = true;
    } else {
      if (fields.size() != t.columns.size())
        fail_at(file, record_line,
                "row has " + std::to_string(fields.size()) + " fields; the header has " +
                    std::to_string(t.columns.size()) + " columns");
      t.rows.push_back(std::move(fields));
      t.lines.push_back(record_line);
    }
  }
  if (!have_header) throw InputError(file + ": empty file; expected a header line of column names");
  return t;
}

CsvTable read_csv(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(name + ": cannot read: is a directory");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno != 0 ? errno : ENOENT;
    throw InputError(name + ": cannot read: " + std::generic_category().message(err));
  }
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw InputError(name + ": cannot read: I/O error");
  return parse_csv(s.str(), name);
}

std::optional<double> parse_csv_number(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '-' || text.front() == '+')) return std::nullopt;
  }
  if (text.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  // Out of range ("1e999") still reads as a number; from_chars leaves value unset then.
  if (ec == std::errc::result_out_of_range && end == text.data() + text.size()) {
    const std::string s(text);
    return std::strtod(s.c_str(), nullptr);
  }
  if (ec != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace ricochet
