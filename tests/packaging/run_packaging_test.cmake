# Installs the just-built combabc into a scratch prefix and builds against it the downstream
# project (downstream/): the README's library example (EXAMPLE_DIR) with the engine alone, and a
# program linking every component. Runs both and checks the example's numbers, and that the
# README's code is the example's.
# -D: BUILD_DIR, SOURCE_DIR (downstream/), EXAMPLE_DIR, README, WORK_DIR (scratch), GENERATOR.
cmake_minimum_required(VERSION 3.25)  # this script's policies
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "packaging test step failed (${rc}): ${ARGN}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release -DEXAMPLE_DIR=${EXAMPLE_DIR})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/everything)

# The exact posterior by hand (examples/library/main.cpp): supports 1-3 identified as fixed, free,
# fixed; supports 4-6 keep their prior. The program itself fails unless ABC-SMC agrees with it.
execute_process(COMMAND ${WORK_DIR}/build/library_example/library_example
  RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "library example:\n${out}")
foreach(row "      1  0.500  1.0000" "      2  0.500  0.0000" "      3  0.500  1.0000"
    "      4  0.300  0.3000" "      5  0.500  0.5000" "      6  0.700  0.7000"
    "ABC-SMC agrees with the exact posterior")
  string(FIND "${out}" "${row}" at)
  if(NOT rc EQUAL 0 OR at LESS 0)
    message(FATAL_ERROR "library example: status ${rc}, no line with '${row}'")
  endif()
endforeach()

# Every C++ block of the README's "As a library" is part of the example (indentation aside).
file(READ ${README} readme)
string(FIND "${readme}" "## As a library" at)
string(SUBSTRING "${readme}" ${at} -1 section)
string(FIND "${section}" "\n## " end)
string(SUBSTRING "${section}" 0 ${end} section)
file(READ ${EXAMPLE_DIR}/main.cpp example)
string(REGEX REPLACE "\n +" "\n" example "${example}")
set(blocks 0)
while(TRUE)
  string(FIND "${section}" "```cpp\n" begin)
  if(begin LESS 0)
    break()
  endif()
  math(EXPR begin "${begin} + 7")
  string(SUBSTRING "${section}" ${begin} -1 section)
  string(FIND "${section}" "```" end)
  string(SUBSTRING "${section}" 0 ${end} block)
  string(SUBSTRING "${section}" ${end} -1 section)
  string(REGEX REPLACE "\n +" "\n" block "\n${block}")
  string(FIND "${example}" "${block}" found)
  if(found LESS 0)
    message(FATAL_ERROR "README.md, \"As a library\": this block is not in ${EXAMPLE_DIR}/main.cpp:"
      "${block}")
  endif()
  math(EXPR blocks "${blocks} + 1")
endwhile()
if(blocks EQUAL 0)
  message(FATAL_ERROR "README.md, \"As a library\": no C++ block")
endif()
