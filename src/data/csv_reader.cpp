#include "combabc/data/csv_reader.hpp"

#include <csv.h>

#include <algorithm>
#include <new>
#include <unordered_map>
#include <utility>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

// A line with nothing but blanks, or whose first non-blank character is '#'; `line` may end in
// its line break.
bool IsBlankOrComment(std::string_view line) {
  const std::size_t first = line.find_first_not_of(" \t");
  return first == std::string_view::npos || line[first] == '\r' || line[first] == '\n' ||
         line[first] == '#';
}

std::string Cells(std::size_t n) { return std::to_string(n) + (n == 1 ? " cell" : " cells"); }

}  // namespace

// libcsv's parser state, in strict mode: a quote inside an unquoted cell, text after a closing
// quote and (at the end) an unclosed quoted cell are errors rather than guessed at.
struct CsvReader::Parser {
  csv_parser state{};
  Parser() {
    if (csv_init(&state, CSV_STRICT | CSV_STRICT_FINI) != 0) throw std::bad_alloc();
  }
  ~Parser() { csv_free(&state); }
  Parser(const Parser&) = delete;
  Parser& operator=(const Parser&) = delete;
};

CsvReader::CsvReader(std::string_view text, std::string path)
    : text_(text), path_(std::move(path)), parser_(std::make_unique<Parser>()) {
  if (text_.starts_with("\xEF\xBB\xBF")) text_.remove_prefix(3);  // UTF-8 byte order mark
}

CsvReader::~CsvReader() = default;

std::string CsvReader::ColumnName(std::size_t index) const {
  return index < header_.size() ? header_[index] : std::string();
}

void CsvReader::Fail(const std::string& message, int line, std::size_t index) const {
  throw Error(
      ErrorKind::kData, message, path_, line, ColumnName(index), static_cast<int>(index) + 1);
}

// libcsv calls these from C: they must not throw, so a failed allocation is only noted here and
// thrown by ReadRecord once the parser has returned.
void CsvReader::OnCell(void* data, std::size_t size, void* self) {
  auto* reader = static_cast<CsvReader*>(self);
  const std::size_t kept = reader->width_ > 0 ? reader->width_ : kMaxCsvColumns;
  const std::size_t index = reader->cell_count_++;
  if (index >= kept) return;  // counted only: the record is refused for its width
  const std::string_view cell =
      data == nullptr ? std::string_view() : std::string_view(static_cast<const char*>(data), size);
  try {
    if (index < reader->cells_.size()) {
      reader->cells_[index].assign(cell);
    } else {
      reader->cells_.emplace_back(cell);
    }
  } catch (const std::bad_alloc&) {
    reader->out_of_memory_ = true;
  }
}

void CsvReader::OnRecordEnd(int /*terminator*/, void* self) {
  auto* reader = static_cast<CsvReader*>(self);
  reader->record_done_ = true;
  reader->record_open_ = false;
}

// The next line of text_ with its line break (LF, CRLF or a lone CR), so that libcsv sees the
// text unchanged and every record ends at the end of a line.
bool CsvReader::NextPhysicalLine(std::string_view* line) {
  if (at_ >= text_.size()) return false;
  std::size_t end = std::min(text_.find_first_of("\r\n", at_), text_.size());
  if (end < text_.size() && text_[end] == '\r') ++end;  // CR, or the CR of CRLF
  if (end < text_.size() && text_[end] == '\n') ++end;  // LF, or the LF of CRLF
  *line = text_.substr(at_, end - at_);
  at_ = end;
  ++physical_line_;
  return true;
}

// Feeds libcsv line by line until it ends a record (its cells then in cells_, cell_count_ of them,
// at most width_ kept); false when the text ends before another record begins.
bool CsvReader::ReadRecord() {
  cell_count_ = 0;
  record_done_ = false;
  std::string_view line;
  while (NextPhysicalLine(&line)) {
    if (!record_open_) {
      if (IsBlankOrComment(line)) continue;
      record_open_ = true;
      record_line_ = physical_line_;
    }
    const std::size_t used =
        csv_parse(&parser_->state, line.data(), line.size(), OnCell, OnRecordEnd, this);
    if (out_of_memory_) throw std::bad_alloc();
    if (used < line.size()) {
      if (csv_error(&parser_->state) != CSV_EPARSE) throw std::bad_alloc();
      Fail(parser_->state.quoted != 0
               ? "text after the closing quote of a quoted cell (a quote inside quotes is "
                 "written \"\")"
               : "a quote inside an unquoted cell (enclose the cell in quotes and write the "
                 "quote as \"\")",
           physical_line_,
           cell_count_);
    }
    if (record_done_) return true;
  }
  if (!record_open_) return false;
  // The last line had no line break, or a quoted cell is still open.
  if (csv_fini(&parser_->state, OnCell, OnRecordEnd, this) != 0) {
    Fail("quoted cell not closed: the file ends inside it", record_line_, cell_count_);
  }
  if (out_of_memory_) throw std::bad_alloc();
  return record_done_;
}

const std::vector<std::string>& CsvReader::ReadHeader() {
  if (!ReadRecord()) throw Error(ErrorKind::kData, "empty file (no header row)", path_, 1);
  if (cell_count_ > kMaxCsvColumns) {
    Fail("more than " + std::to_string(kMaxCsvColumns) + " columns", record_line_, kMaxCsvColumns);
  }
  width_ = cell_count_;
  header_.assign(cells_.begin(), cells_.begin() + static_cast<std::ptrdiff_t>(width_));
  // A repeated name would make the column a config names ambiguous; empty names (a spreadsheet's
  // unnamed index or trailing columns) cannot be named and may repeat.
  std::unordered_map<std::string_view, std::size_t> seen;
  for (std::size_t k = 0; k < header_.size(); ++k) {
    if (header_[k].empty()) continue;
    const auto [it, inserted] = seen.emplace(header_[k], k);
    if (!inserted) {
      Fail("duplicate column name (also column " + std::to_string(it->second + 1) + ")",
           record_line_,
           k);
    }
  }
  return header_;
}

bool CsvReader::Next() {
  if (!ReadRecord()) return false;
  if (width_ == 0) {  // the first record, without a header
    if (cell_count_ > kMaxCsvColumns) {
      Fail(
          "more than " + std::to_string(kMaxCsvColumns) + " columns", record_line_, kMaxCsvColumns);
    }
    width_ = cell_count_;
    return true;
  }
  if (cell_count_ != width_) {
    const std::string expected =
        (header_.empty() ? "; the first row has " : "; the header has ") + std::to_string(width_);
    if (cell_count_ < width_) {
      Fail("row has " + Cells(cell_count_) + expected + "; the column is missing",
           record_line_,
           cell_count_);
    }
    Fail("row has " + Cells(cell_count_) + expected +
             " (a comma in an unquoted cell? enclose such cells in double quotes)",
         record_line_,
         width_);
  }
  return true;
}

}  // namespace combabc
