# Instrumented builds (off by default; CI builds FRAGG_SANITIZE=address for the fuzz corpus replay
# alone, scripts/sanitize.sh replay):
# - FRAGG_FUZZ=ON (clang only): every library with -fsanitize=fuzzer-no-link,address,undefined
#   and one libFuzzer binary per reader, fragg_fuzz_<target> (test/fuzz/; scripts/fuzz.sh).
# - FRAGG_SANITIZE=address (ASan + UBSan) or thread (TSan), gcc or clang: the whole build
#   instrumented for the tests (scripts/sanitize.sh).
# A UBSan finding stops the program (no recovery), so tests and fuzzers fail on it.
option(FRAGG_FUZZ "Build the libFuzzer targets (clang; instruments every library)" OFF)
set(FRAGG_SANITIZE "" CACHE STRING "Sanitizer build: '' | address (ASan+UBSan) | thread (TSan)")

set(_fragg_san_flags "")
if(FRAGG_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "FRAGG_FUZZ needs clang (libFuzzer): -DCMAKE_CXX_COMPILER=clang++-14")
  endif()
  if(FRAGG_SANITIZE)
    message(FATAL_ERROR "FRAGG_FUZZ already builds with ASan+UBSan; leave FRAGG_SANITIZE empty")
  endif()
  set(_fragg_san_flags -fsanitize=address,undefined)
  add_compile_options(-fsanitize=fuzzer-no-link)
elseif(FRAGG_SANITIZE STREQUAL "address")
  set(_fragg_san_flags -fsanitize=address,undefined)
elseif(FRAGG_SANITIZE STREQUAL "thread")
  set(_fragg_san_flags -fsanitize=thread)
elseif(FRAGG_SANITIZE)
  message(FATAL_ERROR "FRAGG_SANITIZE must be empty, address or thread (not ${FRAGG_SANITIZE})")
endif()
if(_fragg_san_flags)
  # -g1: line tables for the reports (full debug info only slows the build down).
  add_compile_options(${_fragg_san_flags} -fno-sanitize-recover=undefined -fno-omit-frame-pointer
    -g1)
  add_link_options(${_fragg_san_flags})
  message(STATUS "fragg_map: instrumented build: ${_fragg_san_flags} (fuzz: ${FRAGG_FUZZ})")
endif()
