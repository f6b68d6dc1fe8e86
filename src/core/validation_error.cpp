#include "combabc/core/validation_error.hpp"

#include <cctype>

namespace combabc {

std::string ValidationError::Detail() const {
  if (value.empty()) return field + " " + constraint;
  return field + " = " + value + "; " + constraint;
}

std::string ValidationError::Message() const {
  return owner.empty() ? Detail() : owner + "::" + Detail();
}

std::string ValidationError::Member() const { return field.substr(0, field.find_first_of("[.:")); }

ValidationError ValidationError::FromMessage(const std::string& message) {
  ValidationError e;
  const std::size_t colons = message.find("::");
  std::size_t end = 0;
  if (colons != std::string::npos) {
    e.owner = message.substr(0, colons);
    end = colons + 2;
  }
  const std::size_t begin = end;
  auto in_field = [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '[' || ch == ']' ||
           ch == '.';
  };
  while (end < message.size() && in_field(message[end])) ++end;
  e.field = message.substr(begin, end - begin);
  const std::string rest = message.substr(end);
  const std::size_t semicolon = rest.find("; ");
  if (rest.rfind(" = ", 0) == 0 && semicolon != std::string::npos) {
    e.value = rest.substr(3, semicolon - 3);
    e.constraint = rest.substr(semicolon + 2);
  } else {
    e.constraint = rest.empty() ? rest : rest.substr(1);
  }
  return e;
}

bool ExplainValidation(bool valid, const ValidationError& error, std::string* why) {
  if (!valid && why != nullptr) *why = error.Message();
  return valid;
}

}  // namespace combabc
