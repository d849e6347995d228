# Cross compiling fact for 64-bit ARM Linux (aarch64, e.g. Jetson Orin class boards) on an x86-64
# Debian 12 host, against a Debian bookworm arm64 sysroot. scripts/cross-build-arm64.sh makes the
# sysroot and uses this file; by hand:
#   cmake -S . -B build-arm64/aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake \
#         -DFACT_ARM64_SYSROOT=$PWD/build-arm64/sysroot
# Needs Debian g++-aarch64-linux-gnu; qemu-user (qemu-aarch64) to run the tests on the host.
#   - compilers: aarch64-linux-gnu-gcc / -g++ with --sysroot=FACT_ARM64_SYSROOT
#   - headers, libraries and CMake packages only from the sysroot; programs (lcm-gen, javac,
#     pkg-config) from the host
#   - pkg-config reads only the sysroot's .pc files (PKG_CONFIG_LIBDIR), paths prefixed with it
#   - CMAKE_CROSSCOMPILING_EMULATOR = qemu-aarch64 -L <sysroot>: ctest and gtest_discover_tests run
#     the arm64 test executables through it (no binfmt handler is needed)
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# The sysroot: -DFACT_ARM64_SYSROOT=... or the environment variable of the same name. Passed on to
# CMake's try_compile projects, which read this file again.
if(NOT FACT_ARM64_SYSROOT AND DEFINED ENV{FACT_ARM64_SYSROOT})
  set(FACT_ARM64_SYSROOT "$ENV{FACT_ARM64_SYSROOT}")
endif()
if(NOT FACT_ARM64_SYSROOT OR NOT EXISTS "${FACT_ARM64_SYSROOT}/usr/include")
  message(FATAL_ERROR "aarch64-linux-gnu toolchain: FACT_ARM64_SYSROOT='${FACT_ARM64_SYSROOT}' is not a "
    "Debian arm64 sysroot (no usr/include in it); make one with scripts/cross-build-arm64.sh")
endif()
set(FACT_ARM64_SYSROOT "${FACT_ARM64_SYSROOT}" CACHE PATH "Debian bookworm arm64 sysroot")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES FACT_ARM64_SYSROOT)
set(CMAKE_SYSROOT "${FACT_ARM64_SYSROOT}")

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

set(CMAKE_FIND_ROOT_PATH "${FACT_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (the host's) must not see the host's x86-64 .pc files.
set(ENV{PKG_CONFIG_DIR} "")
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_LIBDIR}
  "${FACT_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${FACT_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${FACT_ARM64_SYSROOT}")

# Running arm64 executables on the host (tests, gtest discovery): qemu user mode, with the
# sysroot as the library prefix (the ELF interpreter and shared libraries come from there).
if(NOT CMAKE_CROSSCOMPILING_EMULATOR)
  find_program(FACT_QEMU_AARCH64 qemu-aarch64)
  if(FACT_QEMU_AARCH64)
    set(CMAKE_CROSSCOMPILING_EMULATOR "${FACT_QEMU_AARCH64};-L;${FACT_ARM64_SYSROOT}")
  endif()
endif()
