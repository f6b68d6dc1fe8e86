#pragma once
// combabc.CustomPrior: a prior over one or more reals given by two Python callables, a normalised
// log density and a sampler (combabc::MakeCustomPrior; docs/python.md, "Custom priors").
#include <pybind11/pybind11.h>

namespace combabc::python {

// Adds CustomPrior to the module.
void RegisterPriors(pybind11::module_& m);

}  // namespace combabc::python
