// Typed exceptions thrown by the core. The core never calls exit().
#pragma once

#include <stdexcept>
#include <string>

namespace fragg {

/// A caller passed a value the map cannot use (bad parameter, NaN pose, unknown option).
class InvalidArgument : public std::invalid_argument {
 public:
  explicit InvalidArgument(const std::string& what) : std::invalid_argument(what) {}
};

/// A file could not be read or written, or its contents are malformed.
class IoError : public std::runtime_error {
 public:
  explicit IoError(const std::string& what) : std::runtime_error(what) {}
};

/// A CUDA call failed (thrown by the CUDA backend only).
class CudaError : public std::runtime_error {
 public:
  explicit CudaError(const std::string& what) : std::runtime_error(what) {}
};

/// The device ran out of memory (the CUDA backend falls back to the CPU on it).
class CudaOutOfMemory : public CudaError {
 public:
  explicit CudaOutOfMemory(const std::string& what) : CudaError(what) {}
};

}  // namespace fragg
