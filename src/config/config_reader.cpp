#include "config_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "combabc/core/error.hpp"

namespace combabc::config_internal {
namespace {

std::string Format(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

}  // namespace

const char* TypeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::none:
      return "nothing";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
  }
  return "a value";
}

int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

TableReader::TableReader(const toml::table& table, std::string prefix, const std::string& path)
    : table_(&table), prefix_(std::move(prefix)), path_(&path) {}

int TableReader::line() const { return LineOf(*table_); }

std::string TableReader::Key(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

int TableReader::Line(std::string_view key) const {
  const toml::node* node = table_->get(key);
  return node ? LineOf(*node) : line();
}

bool TableReader::Has(std::string_view key) const { return table_->get(key) != nullptr; }

void TableReader::Fail(std::string_view key, const std::string& message) const {
  throw Error(ErrorKind::kConfig, message, path(), Line(key), Key(key));
}

void TableReader::FailAt(const toml::node& node,
                         const std::string& dotted,
                         const std::string& message) const {
  throw Error(ErrorKind::kConfig, message, path(), LineOf(node), dotted);
}

const toml::node* TableReader::Get(std::string_view key) {
  if (std::find(asked_.begin(), asked_.end(), key) == asked_.end()) asked_.emplace_back(key);
  const toml::node* node = table_->get(key);
  if (node) read_.emplace_back(key);
  return node;
}

const toml::node* TableReader::Raw(std::string_view key) { return Get(key); }

std::optional<bool> TableReader::Bool(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_boolean()) Fail(key, std::string("expected a boolean, got ") + TypeName(*node));
  return node->as_boolean()->get();
}

std::optional<std::string> TableReader::String(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_string()) Fail(key, std::string("expected a string, got ") + TypeName(*node));
  return node->as_string()->get();
}

std::optional<double> TableReader::Number(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_number()) Fail(key, std::string("expected a number, got ") + TypeName(*node));
  const double value = node->value<double>().value_or(0.0);
  if (std::isnan(value)) Fail(key, "must not be nan");
  return value;
}

std::optional<std::int64_t> TableReader::Integer(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_integer()) Fail(key, std::string("expected an integer, got ") + TypeName(*node));
  return node->as_integer()->get();
}

std::optional<std::vector<double>> TableReader::Numbers(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_array()) {
    Fail(key, std::string("expected an array of numbers, got ") + TypeName(*node));
  }
  std::vector<double> out;
  const toml::array& array = *node->as_array();
  for (std::size_t i = 0; i < array.size(); ++i) {
    const toml::node& element = array[i];
    const std::string dotted = Key(key) + "[" + std::to_string(i) + "]";
    if (!element.is_number()) {
      FailAt(element, dotted, std::string("expected a number, got ") + TypeName(element));
    }
    const double value = element.value<double>().value_or(0.0);
    if (std::isnan(value)) FailAt(element, dotted, "must not be nan");
    out.push_back(value);
  }
  return out;
}

std::optional<std::vector<std::string>> TableReader::Strings(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_array()) {
    Fail(key, std::string("expected an array of strings, got ") + TypeName(*node));
  }
  std::vector<std::string> out;
  const toml::array& array = *node->as_array();
  for (std::size_t i = 0; i < array.size(); ++i) {
    const toml::node& element = array[i];
    if (!element.is_string()) {
      FailAt(element,
             Key(key) + "[" + std::to_string(i) + "]",
             std::string("expected a string, got ") + TypeName(element));
    }
    out.push_back(element.as_string()->get());
  }
  return out;
}

std::optional<TableReader> TableReader::Table(std::string_view key) {
  const toml::node* node = Get(key);
  if (!node) return std::nullopt;
  if (!node->is_table()) Fail(key, std::string("expected a table, got ") + TypeName(*node));
  return TableReader(*node->as_table(), Key(key), path());
}

std::vector<TableReader> TableReader::Tables(std::string_view key) {
  std::vector<TableReader> out;
  const toml::node* node = Get(key);
  if (!node) return out;
  if (!node->is_array_of_tables()) {
    Fail(key,
         std::string("expected an array of tables ([[") + Key(key) + "]]), got " + TypeName(*node));
  }
  const toml::array& array = *node->as_array();
  for (std::size_t i = 0; i < array.size(); ++i) {
    out.emplace_back(*array[i].as_table(), Key(key) + "[" + std::to_string(i) + "]", path());
  }
  return out;
}

double TableReader::NumberIn(std::string_view key, double fallback, double lo, double hi) {
  const std::optional<double> value = Number(key);
  if (!value) return fallback;
  if (!(*value >= lo && *value <= hi)) {
    Fail(key, "is " + Format(*value) + "; must be in [" + Format(lo) + ", " + Format(hi) + "]");
  }
  return *value;
}

int TableReader::IntegerIn(std::string_view key, int fallback, std::int64_t lo, std::int64_t hi) {
  const std::optional<std::int64_t> value = Integer(key);
  if (!value) return fallback;
  if (*value < lo || *value > hi) {
    Fail(key,
         "is " + std::to_string(*value) + "; must be in [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
  }
  return static_cast<int>(*value);
}

void TableReader::Finish() const {
  for (auto&& [key, node] : *table_) {
    const std::string name(key.str());
    if (std::find(read_.begin(), read_.end(), name) == read_.end()) {
      std::string known;
      for (const std::string& k : asked_) known += (known.empty() ? "" : ", ") + k;
      throw Error(ErrorKind::kConfig,
                  "unknown key" + (known.empty() ? std::string(" (this table takes none)")
                                                 : "; expected one of: " + known),
                  path(),
                  LineOf(node),
                  Key(name));
    }
  }
}

void Note(std::map<std::string, Source>& map,
          const std::string& field,
          const TableReader& t,
          std::string_view key) {
  if (t.Has(key)) map[field] = {t.Key(key), t.Line(key)};
}

std::string OneOf(std::initializer_list<const char*> names) {
  std::string out;
  for (const char* n : names) out += std::string(out.empty() ? "" : ", ") + '"' + n + '"';
  return out;
}

std::pair<double, double> WindowKey(TableReader& t, std::string_view key, double metres_per_unit) {
  const auto w = t.Numbers(key);
  if (!w || w->size() != 2) {
    t.Fail(key, "expected [from, to] (two numbers in the data's position unit)");
  }
  if (!((*w)[0] < (*w)[1]) || !std::isfinite((*w)[0]) || !std::isfinite((*w)[1])) {
    t.Fail(key, "must be [from, to] with from < to, both finite");
  }
  return {(*w)[0] * metres_per_unit, (*w)[1] * metres_per_unit};
}

}  // namespace combabc::config_internal
