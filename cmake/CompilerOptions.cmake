# Per-target warnings (as KISS-ICP's cmake/CompilerOptions.cmake) and the sanitizer build.
function(lasercell_set_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  if(LASERCELL_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(LASERCELL_SANITIZE AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12 reports -Wmaybe-uninitialized inside libstdc++'s std::regex / std::function when
    # ASan instruments them (a known false positive of that pairing); the normal build keeps it.
    target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
  endif()
endfunction()

if(LASERCELL_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  # -O1 with small-function inlining (after the build type's -O3, so it wins): GCC 12 with ASan
  # at -O3 takes ~5x the normal compile time on Ceres-heavy files (calib/intrinsics.cpp: 82 s vs
  # 16 s), at this level ~2.5x (42 s). The inlining keeps Eigen's tiny functions from running
  # as calls, so the tests do not get slower than at -O1 (measured: same 18 CPU-min for the
  # whole suite). Keeps the CI's cold build + tests near its 30-minute budget; the tests run the
  # same code paths.
  # clang (scripts/test's sanitizer build) compiles as fast at -O2 as at -O1 (43 s vs 44 s on
  # calib/intrinsics.cpp with ASan, UBSan and edge coverage), and the image renderer's test runs
  # 23 % faster (26.1 -> 20.2 s), so clang keeps -O2.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    add_compile_options(-O1 -finline-small-functions -finline-functions)
  else()
    add_compile_options(-O2)
  endif()
  # Under ASan, Eigen stops trusting glibc's 16-byte malloc alignment (__SANITIZE_ADDRESS__) and
  # switches to its offset-pointer aligned malloc, while Debian's libceres (not instrumented)
  # uses plain malloc/free: Eigen objects crossing that boundary (GradientChecker results,
  # Covariance blocks) are then freed with the wrong function. Keep the two in agreement.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
  add_link_options(-fsanitize=address,undefined)
endif()

# ThreadSanitizer (scripts/test-threads): core/parallel.hpp then runs its loops on std::thread,
# since Debian's libtbb is not instrumented. -O1 as in the GCC ASan build; -g for the race reports'
# source lines.
if(LASERCELL_SANITIZE_THREAD)
  if(LASERCELL_SANITIZE)
    message(FATAL_ERROR "LASERCELL_SANITIZE_THREAD and LASERCELL_SANITIZE exclude each other: "
                        "ThreadSanitizer cannot be combined with AddressSanitizer")
  endif()
  add_compile_options(-fsanitize=thread -O1 -g -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()

# libFuzzer (tests/fuzz): clang's coverage instrumentation in every library, so the fuzz
# executables (linked with -fsanitize=fuzzer) see the parsers' branches. Only with the sanitizers:
# a fuzzer without ASan/UBSan misses the memory errors it is there to find.
if(LASERCELL_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang" OR NOT LASERCELL_SANITIZE)
    message(FATAL_ERROR "LASERCELL_FUZZ needs clang and LASERCELL_SANITIZE=ON: configure with "
                        "CC=clang CXX=clang++ -DLASERCELL_SANITIZE=ON -DLASERCELL_FUZZ=ON")
  endif()
  # full: libFuzzer's own instrumentation (edges and comparison tracing), for long fuzz runs
  # (scripts/build-fuzz). edges: edge counters only, no comparison tracing, which makes numeric
  # code (kd-tree searches, Ceres solves) 2-13x slower: scripts/test runs the whole suite and the
  # fuzz smoke from this one sanitizer build instead of building every library twice.
  set(LASERCELL_FUZZ_COVERAGE "full" CACHE STRING "Coverage of the libraries: full or edges")
  if(LASERCELL_FUZZ_COVERAGE STREQUAL "full")
    add_compile_options(-fsanitize=fuzzer-no-link)
    add_link_options(-fsanitize=fuzzer-no-link)
  elseif(LASERCELL_FUZZ_COVERAGE STREQUAL "edges")
    add_compile_options(-fsanitize-coverage=inline-8bit-counters,indirect-calls,pc-table)
  else()
    message(FATAL_ERROR "LASERCELL_FUZZ_COVERAGE must be full or edges, not "
                        "'${LASERCELL_FUZZ_COVERAGE}'")
  endif()
endif()

# One library per module folder: lasercell_<name>, alias lasercell::<name>.
function(lasercell_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(lasercell_${name} ${ARG_SOURCES})
  add_library(lasercell::${name} ALIAS lasercell_${name})
  target_include_directories(lasercell_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/lasercell>)
  target_link_libraries(lasercell_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  lasercell_set_options(lasercell_${name})
endfunction()
