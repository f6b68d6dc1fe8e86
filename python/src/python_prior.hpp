#pragma once
// combabc.CustomPrior (a prior over one or more reals given by two Python callables, a normalised
// log density and a sampler: combabc::MakeCustomPrior) and combabc.MultivariateNormalPrior
// (combabc::MakeMultivariateNormalPrior): the joint priors a Problem takes as priors=
// (docs/python.md, "Custom and joint priors").
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <utility>

#include "combabc/params/joint_prior.hpp"
#include "python_call.hpp"

namespace combabc::python {

// What both Python prior classes are, for a run (SmcRequest's joint priors): the C++ prior and how
// it prints. Python's CustomPrior and MultivariateNormalPrior derive from it
// (combabc._core.JointPrior).
class PythonJointPrior {
 public:
  PythonJointPrior(std::shared_ptr<const JointPrior> prior,
                   std::string repr,
                   std::shared_ptr<FirstPythonError> error = nullptr)
      : prior_(std::move(prior)), repr_(std::move(repr)), error_(std::move(error)) {}
  int dimension() const { return prior_->dimension(); }
  const std::shared_ptr<const JointPrior>& prior() const { return prior_; }
  const std::string& repr() const { return repr_; }
  // A custom prior's first Python exception, which the run raises again as itself (null for a
  // prior without Python code).
  FirstPythonError* error() const { return error_.get(); }

 private:
  std::shared_ptr<const JointPrior> prior_;
  std::string repr_;
  std::shared_ptr<FirstPythonError> error_;
};

// Adds JointPrior, CustomPrior and MultivariateNormalPrior to the module.
void RegisterPriors(pybind11::module_& m);

}  // namespace combabc::python
