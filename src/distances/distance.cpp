#include "combabc/distances/distance.hpp"

namespace combabc {

const char* ToString(ComponentKind kind) {
  switch (kind) {
    case ComponentKind::kThreshold:
      return "threshold";
    case ComponentKind::kIndicator:
      return "indicator";
  }
  return "?";
}

}  // namespace combabc
