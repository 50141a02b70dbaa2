# Precompiled headers: the test command builds the tree twice (Release, ASan+UBSan) on two cores,
# and most of that time went into parsing the same third-party headers in every file. nlohmann's
# json (about 2.7 s a file at -O3) reaches nearly every file through the octree's metadata and
# the readers; CLI11 (about 9 s, header-only in Debian) every sub-command; GoogleTest every test.
# Each is parsed once per group of targets instead (libraries, tests, the program). Option
# NESTLIGHT_PCH=OFF builds without them, which is also how to check that every file includes what
# it uses.
# The fuzz build (clang, a few libraries) gains little and clang refuses a precompiled header on
# any flag difference, so it builds without.
if(NESTLIGHT_FUZZ)
  option(NESTLIGHT_PCH "Precompile the heavy third-party headers" OFF)
else()
  option(NESTLIGHT_PCH "Precompile the heavy third-party headers" ON)
endif()

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
# the ImGui back-ends (third-party code, none of these headers).
set(NESTLIGHT_PCH_SKIP nestlight_shaders nestlight_pcd nestlight_imgui_backends)
function(nestlight_precompile_tree dir)
  get_property(_targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(t ${_targets})
    get_target_property(_type ${t} TYPE)
    if(t IN_LIST NESTLIGHT_PCH_SKIP OR NOT _type MATCHES "STATIC_LIBRARY|EXECUTABLE")
      continue()
    endif()
    get_target_property(_sources ${t} SOURCES)
    list(LENGTH _sources _n)
    if(_n LESS 2)
      continue()
    endif()
    if(t STREQUAL "nestlight")
      nestlight_precompile(${t} cli <CLI/CLI.hpp>)
    elseif(t MATCHES "_tests$")
      nestlight_precompile(${t} tests <gtest/gtest.h>)
    else()
      nestlight_precompile(${t} libraries)
    endif()
  endforeach()
  get_property(_subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(d ${_subdirs})
    nestlight_precompile_tree(${d})
  endforeach()
endfunction()
