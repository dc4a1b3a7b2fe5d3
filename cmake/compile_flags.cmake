# Warnings everywhere; no floating-point contraction so the CPU and CUDA backends compute the
# same bits (nvcc gets --fmad=false).
function(fragg_target_flags target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wno-unused-parameter -ffp-contract=off>)
endfunction()
