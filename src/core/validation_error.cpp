#include "combabc/core/validation_error.hpp"

namespace combabc {

std::string ValidationError::Detail() const {
  if (value.empty()) return field + " " + constraint;
  return field + " = " + value + "; " + constraint;
}

std::string ValidationError::Message() const {
  return owner.empty() ? Detail() : owner + "::" + Detail();
}

std::string ValidationError::Member() const { return field.substr(0, field.find_first_of("[.:")); }

bool ExplainValidation(bool valid, const ValidationError& error, std::string* why) {
  if (!valid && why != nullptr) *why = error.Message();
  return valid;
}

}  // namespace combabc
