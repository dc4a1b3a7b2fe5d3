# The CUDA backend is built when a CUDA compiler is found (nvcc need not have a GPU beside it:
# CI compiles the kernels without one). FRAGG_WITH_CUDA=OFF leaves it out.
option(FRAGG_WITH_CUDA "Build the CUDA backend when a CUDA compiler is found" ON)
# The demo's first run: kernels for the GPU of this machine only (CMake >= 3.24; needs a GPU).
option(FRAGG_CUDA_NATIVE "Compile the CUDA kernels for this machine's GPU only (native)" OFF)
set(FRAGG_HAVE_CUDA OFF)
if(FRAGG_WITH_CUDA)
  if(NOT CMAKE_CUDA_COMPILER AND NOT DEFINED ENV{CUDACXX} AND EXISTS /usr/local/cuda/bin/nvcc)
    set(CMAKE_CUDA_COMPILER /usr/local/cuda/bin/nvcc)
  endif()
  include(CheckLanguage)
  check_language(CUDA)
  if(CMAKE_CUDA_COMPILER)
    # Turing to Hopper as machine code, plus PTX for newer GPUs. Override with
    # -DCMAKE_CUDA_ARCHITECTURES=90 to build faster for one GPU.
    if(FRAGG_CUDA_NATIVE)
      set(CMAKE_CUDA_ARCHITECTURES native)
    elseif(NOT DEFINED CMAKE_CUDA_ARCHITECTURES OR CMAKE_CUDA_ARCHITECTURES STREQUAL "native")
      set(CMAKE_CUDA_ARCHITECTURES "75-real;80-real;86-real;87-real;89-real;90-real;90-virtual")
    endif()
    enable_language(CUDA)
    find_package(CUDAToolkit REQUIRED)
    set(CMAKE_CUDA_STANDARD 17)
    set(CMAKE_CUDA_STANDARD_REQUIRED ON)
    set(FRAGG_HAVE_CUDA ON)
    message(STATUS "fragg_map: CUDA backend on (nvcc ${CMAKE_CUDA_COMPILER_VERSION}, "
                   "architectures ${CMAKE_CUDA_ARCHITECTURES})")
  else()
    message(STATUS "fragg_map: no CUDA compiler found: CPU backend only")
  endif()
endif()

# Device code computes the same bits as the host code: no FMA contraction, IEEE division and
# square root (nvcc's defaults, spelled out).
function(fragg_cuda_flags target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CUDA>:--fmad=false -prec-div=true -prec-sqrt=true
      -Xcompiler=-ffp-contract=off -Xcompiler=-Wall>)
endfunction()
