# Warnings and sanitizers, applied per target so that third-party headers stay quiet.
if(COMBABC_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()
# Fuzzing (docs/fuzzing.md): everything is instrumented for libFuzzer's coverage feedback and
# checked by ASan + UBSan (UB aborts, so it counts as a finding); only the targets in fuzz/ link
# libFuzzer itself (-fsanitize=fuzzer, which brings its main).
if(COMBABC_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "COMBABC_FUZZ needs clang (libFuzzer): configure with CC=clang-14 "
      "CXX=clang++-14 (Debian packages clang-14 and libclang-rt-14-dev)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
    -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()
if(COMBABC_TSAN)
  if(COMBABC_SANITIZE)
    message(FATAL_ERROR "COMBABC_TSAN and COMBABC_SANITIZE exclude each other: use two build dirs")
  endif()
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()

function(combabc_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12 at -O3 reports impossible sizes for inlined std::string / std::vector comparisons
    # (GCC bugs 105329, 105651): false positives, silenced so -Werror stays usable.
    target_compile_options(${target} PRIVATE -Wno-restrict -Wno-stringop-overread
      -Wno-stringop-overflow)
  endif()
  if(COMBABC_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
