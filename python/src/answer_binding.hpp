#pragma once
// combabc._core.answer: a history's answer (export/answer.hpp) as plain Python objects, the numbers
// the terminal prints and summary.json's "answer" holds, for History.answer() (docs/python.md).
#include <pybind11/pybind11.h>

#include "combabc/export/answer.hpp"

namespace combabc::python {

// Keys: wave, waves, complete, exact, estimator, termination, verdict_level, particles,
// distinct, tempered, temperatures (list of (component, temperature)), bits (per bit a dict:
// number, name, position (text or None), p_one, mc_se, verdict), reals (per parameter: name,
// mean, mc_se, sd, sd_se, ess, q05, median, q95), top_configurations (bits, mass, mass_se (None
// when exact), fixed) and text (AnswerText: what the terminal prints).
pybind11::dict AnswerToDict(const Answer& answer);

// Registers answer(path): services::ReadAnswer(path) as AnswerToDict's dict.
void BindAnswer(pybind11::module_& m);

}  // namespace combabc::python
