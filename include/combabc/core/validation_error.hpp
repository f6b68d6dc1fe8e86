#pragma once
// Why an options struct failed its IsValid check, as data (owner, field, value, constraint): the
// config layer reports it at the config key that set `field` without reading the sentence back,
// and Message() is the one-line sentence the library has always given
// ("SensorOptions::load_x = 1.2; must lie on the plate, in [0, 0.9] m").
#include <string>

namespace combabc {

struct ValidationError {
  // The struct whose check failed ("SensorOptions"); empty where the caller names it (a schedule's
  // "where").
  std::string owner;
  // The field as C++ names it, with any index or member path below it: "load_x",
  // "output_positions[3]", "layers[2]::thickness", "load_cases[1].load_x", "tempering.values".
  std::string field;
  // The value as the message states it ("1.2"; for a comparison, its right side too:
  // "0.5 > values[0]"); empty where the message states none.
  std::string value;
  // What was expected, or with no value the statement after the field: "must be in [0, 1]",
  // "has 3 entries; must have one per wave (num_waves = 2)".
  std::string constraint;

  // "owner::field = value; constraint" (without a value "owner::field constraint"; without an
  // owner no "owner::").
  std::string Message() const;
  // Message() without "owner::".
  std::string Detail() const;
  // The member of the owner that `field` lies in: "layers" for "layers[2]::thickness",
  // "tempering" for "tempering.values[1]".
  std::string Member() const;
};

// The string form of an IsValid check: returns `valid`; when it is false and `why` is not null,
// writes error.Message() there.
bool ExplainValidation(bool valid, const ValidationError& error, std::string* why);

}  // namespace combabc
