# Cross build for a Raspberry Pi 3/4/5 running 64-bit Raspberry Pi OS or Debian 12 (arm64),
# on a Debian 12 amd64 host: `make pi` uses it for the on-board tree (SWEEPMAP_ONBOARD).
# What it needs comes from `tools/ops/setup.sh --pi`:
#  - crossbuild-essential-arm64: aarch64-linux-gnu-gcc/g++, the arm64 libc and libstdc++;
#  - multiarch arm64 packages in /usr/lib/aarch64-linux-gnu (libc, libgpiod, GTest, yaml-cpp's
#    runtime, glib);
#  - the arm64 LCM (liblcm1, liblcm-dev) and yaml-cpp -dev files, which Debian 12 cannot
#    install next to the amd64 ones, unpacked into SWEEPMAP_ARM64_ROOT;
#  - qemu-user-static: the tests run under qemu-aarch64-static (CMAKE_CROSSCOMPILING_EMULATOR,
#    so `ctest` and GTest's test discovery work on this host).
# Host tools (lcm-gen, javac, jar, python3) are the amd64 ones.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT SWEEPMAP_ARM64_ROOT)
  if(DEFINED ENV{SWEEPMAP_ARM64_ROOT})
    set(SWEEPMAP_ARM64_ROOT $ENV{SWEEPMAP_ARM64_ROOT})
  else()
    set(SWEEPMAP_ARM64_ROOT /opt/sweepmap-arm64)
  endif()
endif()
set(SWEEPMAP_ARM64_ROOT ${SWEEPMAP_ARM64_ROOT} CACHE PATH
    "arm64 LCM and yaml-cpp -dev files unpacked by tools/ops/setup.sh --pi")
if(NOT EXISTS ${SWEEPMAP_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig/lcm.pc)
  message(FATAL_ERROR "${SWEEPMAP_ARM64_ROOT} has no arm64 LCM: run tools/ops/setup.sh --pi")
endif()
# try_compile projects see the same settings.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SWEEPMAP_ARM64_ROOT)

# Libraries and CMake package files: the unpacked root first, then the host's multiarch arm64
# folders (CMAKE_LIBRARY_ARCHITECTURE). Programs are the host's.
list(PREPEND CMAKE_PREFIX_PATH ${SWEEPMAP_ARM64_ROOT}/usr)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)

# pkg-config: only arm64 .pc files (lcm.pc from the unpacked root, libgpiod.pc from multiarch).
set(ENV{PKG_CONFIG_LIBDIR}
    "${SWEEPMAP_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# qemu: the arm64 loader and libc of the multiarch libc6:arm64 (/lib/ld-linux-aarch64.so.1),
# and liblcm.so.1 by the build tree's RPATH. Not `-L /usr/aarch64-linux-gnu`: that loader
# (libc6-arm64-cross 2.36-8cross1) with the multiarch libc.so.6 (2.36-9+deb12uN) hangs in
# the first pthread_create.
find_program(SWEEPMAP_QEMU qemu-aarch64-static)
if(SWEEPMAP_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${SWEEPMAP_QEMU})
endif()
