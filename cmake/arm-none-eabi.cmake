# Toolchain file: bare-metal Arm (arm-none-eabi-gcc), used by the MCU
# sub-builds of tests/mcu/cross.  The CPU flags are chosen by the project
# (CT_MCU_CPU), not here, so one file serves Cortex-M0 and Cortex-M4.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CT_ARM_PREFIX arm-none-eabi- CACHE STRING "cross tool prefix")
find_program(CMAKE_C_COMPILER ${CT_ARM_PREFIX}gcc REQUIRED)
find_program(CMAKE_ASM_COMPILER ${CT_ARM_PREFIX}gcc REQUIRED)
find_program(CMAKE_AR ${CT_ARM_PREFIX}ar REQUIRED)
find_program(CMAKE_RANLIB ${CT_ARM_PREFIX}ranlib REQUIRED)
find_program(CMAKE_OBJCOPY ${CT_ARM_PREFIX}objcopy)
find_program(CMAKE_OBJDUMP ${CT_ARM_PREFIX}objdump)
find_program(CT_ARM_NM ${CT_ARM_PREFIX}nm)
find_program(CT_ARM_SIZE ${CT_ARM_PREFIX}size)

# No hosted runtime: the compiler test must not try to link an executable.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
