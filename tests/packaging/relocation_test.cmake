# An install moved to another prefix after `cmake --install` still works: the moved CLI runs a
# small calibration (the 45 cm example, coarse mesh, 2 waves) and draws the report; the moved
# Python module imports and draws one too; a program compiles and links against the moved tree
# with pkg-config; and with the report script taken away, the CLI says where it looked (the moved
# prefix), never falling back to the source tree.
# -D: BUILD_DIR, SOURCE_DIR, WORK_DIR (scratch, in the build tree), CXX, PYTHON (may be empty).
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    # The moved install stays for a look; it is removed when the test passes.
    message(FATAL_ERROR "relocation test step failed (${rc}): ${ARGN} (install in ${moved})")
  endif()
endfunction()
function(expect_file path)
  if(NOT EXISTS ${path})
    message(FATAL_ERROR "relocation test: ${path} was not written")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
# Moved out of the build tree, where a build-tree binary's source-tree fallback cannot apply.
if(DEFINED ENV{TMPDIR})
  set(tmp $ENV{TMPDIR})
else()
  set(tmp /tmp)
endif()
string(RANDOM LENGTH 10 tag)
set(moved ${tmp}/combabc-moved-${tag})
file(RENAME ${WORK_DIR}/prefix ${moved})
if(EXISTS ${WORK_DIR}/prefix)
  message(FATAL_ERROR "relocation test: the prefix was not moved")
endif()

# A small copy of the 45 cm example.
file(READ ${SOURCE_DIR}/examples/sensor-45cm/least_squares.toml config)
foreach(pair "waves = 5;waves = 2" "accepted_per_wave = 500;accepted_per_wave = 40"
    "elements_per_section = 10;elements_per_section = 2"
    "elements_across_width = 6;elements_across_width = 2" "threads = 0;threads = 2")
  list(GET pair 0 from)
  list(GET pair 1 to)
  string(REPLACE "${from}" "${to}" config "${config}")
endforeach()
file(WRITE ${WORK_DIR}/small.toml "${config}")
file(COPY ${SOURCE_DIR}/examples/sensor-45cm/data.csv DESTINATION ${WORK_DIR})

run(${moved}/bin/combabc run ${WORK_DIR}/small.toml -q -o ${WORK_DIR}/cli)
expect_file(${WORK_DIR}/cli/report/index.html)
expect_file(${WORK_DIR}/cli/report/overview.png)

if(PYTHON AND EXISTS ${moved}/lib/python3/dist-packages/combabc)
  set(ENV{PYTHONPATH} ${moved}/lib/python3/dist-packages)
  set(ENV{PYTHONDONTWRITEBYTECODE} 1)
  run(${PYTHON} -c "import combabc, sys
assert combabc.__file__.startswith('${moved}/'), combabc.__file__
h = combabc.run('${WORK_DIR}/small.toml', output_directory='${WORK_DIR}/py', report=True)
assert h.report_directory, 'no report'")
  expect_file(${WORK_DIR}/py/report/overview.png)
endif()

# pkg-config against the moved tree.
file(WRITE ${WORK_DIR}/use.cpp [=[
#include <iostream>
#include "combabc/services/history_tools.hpp"
int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const auto outcome = combabc::services::VerifyHistory(argv[1]);
  for (const auto& line : outcome.lines) std::cout << line << "\n";
  return outcome.ok ? 0 : 1;
}
]=])
set(ENV{PKG_CONFIG_PATH} ${moved}/lib/pkgconfig)
execute_process(COMMAND pkg-config --cflags --libs combabc OUTPUT_VARIABLE flags
  RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "relocation test: pkg-config --cflags --libs combabc failed")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
run(${CXX} ${WORK_DIR}/use.cpp -o ${WORK_DIR}/use ${flags})
run(${WORK_DIR}/use ${WORK_DIR}/cli/history.sqlite)

# Without its report script, the moved CLI says where it looked.
file(REMOVE_RECURSE ${moved}/share/combabc/report)
execute_process(COMMAND ${moved}/bin/combabc report ${WORK_DIR}/cli/history.sqlite
  -o ${WORK_DIR}/cli/again RESULT_VARIABLE rc ERROR_VARIABLE err)
file(REMOVE_RECURSE ${moved})
string(FIND "${err}" "${moved}/share/combabc/report/combabc_report.py" at)
if(NOT rc EQUAL 73 OR at LESS 0)
  message(FATAL_ERROR "relocation test: a missing report script gave status ${rc} and '${err}'; "
    "expected 73 and a message naming ${moved}/share/combabc/report/combabc_report.py")
endif()
message(STATUS "relocation test: ok (${err})")
