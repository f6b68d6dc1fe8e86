#pragma once
// The one CSV reader of the input files (the measured data, [simulator.outputs] coordinates_csv):
// RFC 4180 through Debian's libcsv, with combabc's one-line errors naming file:line, the column
// (1-based) and its header name.
//
// Dialect (docs/config.md, "CSV format"): cells separated by commas; a cell may be enclosed in
// double quotes, and then holds commas, line breaks and doubled quotes ("" is one "); blanks
// around an unquoted cell and around the quotes are dropped; a quote inside an unquoted cell, or
// text after a closing quote, is an error. Lines end in LF, CRLF or a lone CR, each counted as one
// line. Blank lines and lines starting with '#' between records are skipped (provenance notes); a
// UTF-8 byte order mark at the start is ignored. Every record has as many cells as the first one
// (the header); non-empty header names must be distinct.
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace combabc {

// Most columns a CSV may have (docs/config.md, "Limits"): far above any measured profile's, and
// low enough that a file of commas cannot make the reader hold millions of cells.
inline constexpr std::size_t kMaxCsvColumns = 100000;

class CsvReader {
 public:
  // `text` must outlive the reader; `path` names the file in messages only.
  CsvReader(std::string_view text, std::string path);
  ~CsvReader();
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;

  // Reads the first record as the header and returns its names. Throws Error(kData) for an empty
  // file, a header of more than kMaxCsvColumns cells or a repeated non-empty name (naming the
  // line, the column and the name). Call it before the first Next(), or never (a file whose first
  // record may be data: then the first record only fixes the number of cells).
  const std::vector<std::string>& ReadHeader();

  // Reads the next record; false at the end of the text. Throws Error(kData) naming file:line,
  // the column and its header name for malformed quoting, an unterminated quoted cell, or a
  // record with more or fewer cells than the first.
  bool Next();

  // The record just read by Next() (as many cells as the first record).
  const std::vector<std::string>& cells() const { return cells_; }
  // The line the record (or, after ReadHeader, the header) starts on, from 1.
  int line() const { return record_line_; }
  // The header name of column `index` (0-based), or "" without a header.
  std::string ColumnName(std::size_t index) const;

 private:
  struct Parser;
  static void OnCell(void* data, std::size_t size, void* self);
  static void OnRecordEnd(int terminator, void* self);
  bool NextPhysicalLine(std::string_view* line);
  bool ReadRecord();
  [[noreturn]] void Fail(const std::string& message, int line, std::size_t index) const;

  std::string_view text_;
  std::string path_;
  std::unique_ptr<Parser> parser_;
  std::size_t at_ = 0;     // next unread byte of text_
  int physical_line_ = 0;  // lines handed to the parser (or skipped) so far
  int record_line_ = 0;    // where the current record starts
  std::vector<std::string> header_;
  std::size_t width_ = 0;  // cells per record, from the first record; 0 before it
  std::vector<std::string> cells_;
  std::size_t cell_count_ = 0;  // cells of the current record so far, also those not kept
  bool record_open_ = false;    // a record has begun and not ended
  bool record_done_ = false;    // the parser has just ended a record
  bool out_of_memory_ = false;
};

}  // namespace combabc
