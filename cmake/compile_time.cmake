# Compile time of the test command, which builds the tree twice (Release, ASan+UBSan) on two
# cores. Two measures, both per group of targets (libraries, tests, the program):
#
# Precompiled headers. Most of the time went into parsing the same third-party headers in every
# file: nlohmann's json (about 2.7 s a file at -O3) reaches nearly every file through the octree's
# metadata and the readers; CLI11 (about 9 s, header-only in Debian) every sub-command; GoogleTest
# every test. Each is parsed once per group instead. The fuzz build (clang, a few libraries) gains
# little and clang refuses a precompiled header on any flag difference, so it builds without.
#
# Unity builds (CMake's UNITY_BUILD): a precompiled header saves the parsing but not the code
# generation, and every file that registers a sub-command or a test instantiates the same CLI11
# and GoogleTest templates again (the 23 sub-commands took 497 s of CPU at -O3; 71 s as two
# unity files). Files of a target are compiled in batches, so their file-local names share one
# translation unit: helpers in anonymous namespaces must not collide, and a `using namespace` at
# file scope reaches the files after it in the batch (a collision is a compile error, never a
# silent change). Measured on the 2-core machine: Release build 14 -> 7 min, ASan+UBSan build
# 17.7 -> 10 min (docs/PERFORMANCE.md).
#
# -DNESTLIGHT_PCH=OFF -DNESTLIGHT_UNITY=OFF compiles every file on its own, which is how to check
# that each file includes what it uses.
if(NESTLIGHT_FUZZ)
  option(NESTLIGHT_PCH "Precompile the heavy third-party headers" OFF)
else()
  option(NESTLIGHT_PCH "Precompile the heavy third-party headers" ON)
endif()

option(NESTLIGHT_UNITY "Compile the files of each target in batches (CMake UNITY_BUILD)" ON)

set(NESTLIGHT_PCH_COMMON
    <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <memory> <optional>
    <string> <string_view> <unordered_map> <vector> <nlohmann/json.hpp>)

# nestlight_precompile(target group [headers...]): the common set plus the group's own heavy
# headers, compiled once per group: the first target of a group builds the header and the others
# reuse it (every target of the tree compiles with the same flags and definitions, which a
# precompiled header requires; -Winvalid-pch reports one that does not).
function(nestlight_precompile target group)
  if(NOT NESTLIGHT_PCH)
    return()
  endif()
  get_property(_host GLOBAL PROPERTY NESTLIGHT_PCH_HOST_${group})
  if(_host)
    target_precompile_headers(${target} REUSE_FROM ${_host})
  else()
    target_precompile_headers(${target} PRIVATE ${NESTLIGHT_PCH_COMMON} ${ARGN})
    set_property(GLOBAL PROPERTY NESTLIGHT_PCH_HOST_${group} ${target})
  endif()
  target_compile_options(${target} PRIVATE -Winvalid-pch)
  target_link_libraries(${target} PRIVATE nlohmann_json::nlohmann_json)
endfunction()

# Every library and program of the tree under `dir` with more than one source file (one file
# gains nothing), but not the embedded shader strings, PCL's reader (PCL's own definitions) or
# the ImGui back-ends (third-party code, none of these headers). Batches of 8 files keep both
# cores busy on the large targets; the program's 23 files make two batches of 12.
set(NESTLIGHT_SPEED_UP_SKIP nestlight_shaders nestlight_pcd nestlight_imgui_backends)
function(nestlight_speed_up_tree dir)
  get_property(_targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(t ${_targets})
    get_target_property(_type ${t} TYPE)
    if(t IN_LIST NESTLIGHT_SPEED_UP_SKIP OR NOT _type MATCHES "STATIC_LIBRARY|EXECUTABLE")
      continue()
    endif()
    get_target_property(_sources ${t} SOURCES)
    list(LENGTH _sources _n)
    if(_n LESS 2)
      continue()
    endif()
    set(_batch 8)
    if(t STREQUAL "nestlight")
      nestlight_precompile(${t} cli <CLI/CLI.hpp>)
      set(_batch 12)
    elseif(t MATCHES "_tests$")
      nestlight_precompile(${t} tests <gtest/gtest.h>)
    else()
      nestlight_precompile(${t} libraries)
    endif()
    set_target_properties(${t} PROPERTIES UNITY_BUILD ${NESTLIGHT_UNITY} UNITY_BUILD_BATCH_SIZE
                                                                        ${_batch})
  endforeach()
  get_property(_subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(d ${_subdirs})
    nestlight_speed_up_tree(${d})
  endforeach()
endfunction()
