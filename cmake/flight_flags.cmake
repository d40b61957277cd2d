# The flight library's compiler flags, shared by the top-level build, the
# standalone library build (lib/CMakeLists.txt, e.g. for a Cortex-M install)
# and the MCU test builds (tests/mcu/cross).
set(CT_LIB_WARNINGS -Wall -Wextra -Wconversion -Wshadow -Wvla -Werror)

# ct_cpu_flags(<cpu> <out-var>): the code-generation flags for a Cortex-M
# core: soft-float ABI and no FPU instructions (tests/mcu/check_symbols.py
# checks the objects).  FATAL_ERROR for another core.
function(ct_cpu_flags cpu out)
  if(cpu STREQUAL "cortex-m0")
    set(${out} -mcpu=cortex-m0 -mthumb -mfloat-abi=soft PARENT_SCOPE)
  elseif(cpu STREQUAL "cortex-m4")
    set(${out} -mcpu=cortex-m4 -mthumb -mfloat-abi=soft PARENT_SCOPE)
  else()
    message(FATAL_ERROR "the Cortex-M core must be cortex-m0 or cortex-m4, not '${cpu}'")
  endif()
endfunction()
