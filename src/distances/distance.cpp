#include "combabc/distances/distance.hpp"

namespace combabc {}  // namespace combabc
