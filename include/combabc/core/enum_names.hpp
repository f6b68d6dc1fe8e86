#pragma once
// One table per enum for its names (Ceres' types.h): ToString, ParseEnum and the list of choices
// in error messages all read the same table, so the CLI, the config, the history and the
// bindings share one vocabulary and a misspelt value gets the same message everywhere.
//
// An enum opts in by specialising EnumNames next to its declaration:
//   template <> struct EnumNames<Estimator> {
//     static constexpr std::pair<Estimator, const char*> kNames[] = {
//         {Estimator::kPaper, "paper"}, {Estimator::kImportance, "importance"}};
//   };
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace combabc {

template <typename E>
struct EnumNames;

template <typename E>
concept NamedEnum = requires {
  EnumNames<E>::kNames;
};

template <NamedEnum E>
constexpr const char* ToString(E value) {
  for (const auto& [v, name] : EnumNames<E>::kNames) {
    if (v == value) return name;
  }
  return "?";  // only reachable for a value cast from an out-of-range integer
}

template <NamedEnum E>
constexpr std::optional<E> ParseEnum(std::string_view text) {
  for (const auto& [v, name] : EnumNames<E>::kNames) {
    if (text == name) return v;
  }
  return std::nullopt;
}

// "\"a\", \"b\", \"c\"": the allowed names, for messages.
template <NamedEnum E>
std::string EnumChoices() {
  std::string out;
  for (const auto& [v, name] : EnumNames<E>::kNames) {
    out += (out.empty() ? "\"" : ", \"") + std::string(name) + "\"";
  }
  return out;
}

}  // namespace combabc
