// How the tool commands (fit-ltc, precompute, procedural, voxelize, sss-reference) report a failure: one line and
// exit status 1. A bad flag value or input file is an InputError that already names where it is ("kozu fit-ltc:
// --size: expected an integer in [2, 256], got 1", "mesh.obj: ..."); anything else is prefixed with the command.
// Usage errors (an unknown option, a missing argument) are CLI11's, with exit status 2, in kozu.cpp.
#pragma once

#include "core/error.h"

#include <cstdio>
#include <exception>
#include <new>
#include <string>

namespace kozu::app {

inline int report_failure(const std::string& command, const std::exception& e) {
  if (dynamic_cast<const InputError*>(&e))
    std::fprintf(stderr, "error: %s\n", e.what());
  else if (dynamic_cast<const std::bad_alloc*>(&e))
    std::fprintf(stderr, "error: kozu %s: out of memory\n", command.c_str());
  else
    std::fprintf(stderr, "error: kozu %s: %s\n", command.c_str(), e.what());
  return 1;
}

}  // namespace kozu::app
