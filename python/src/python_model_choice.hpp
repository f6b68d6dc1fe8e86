#pragma once
// combabc._core.model_choice: a config's [model_choice] run or enumerated from Python
// (docs/python.md, "Model choice").
#include <pybind11/pybind11.h>

namespace combabc::python {

void RegisterModelChoice(pybind11::module_& m);

}  // namespace combabc::python
