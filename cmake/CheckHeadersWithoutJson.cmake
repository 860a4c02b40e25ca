# JSON is the I/O layer's way of writing summary.json, chunk.json and `eval
# --json`, not part of any interface: no public header (cmake/PublicHeaders.cmake)
# includes nlohmann/json, and of the private ones only the I/O layer's
# writers listed below do. Run by CTest (test HeadersWithoutJson):
#   cmake -DROOT=<source dir> -P cmake/CheckHeadersWithoutJson.cmake
# Fails naming every offending header (scripts/install_test.sh checks the
# installed headers transitively).
cmake_minimum_required(VERSION 3.16)  # if(IN_LIST)
#
# The private headers that build JSON (never public):
#   api/result_json.h       eval --json, merged chunks, run's summary hook (live)
#   api/refine_checkpoint.h, api/survey_ties.h   summary.json pieces of refine and merge
#   config/config_json.h    the resolved configuration of summary.json
#   outputs/deviation_outputs.h, outputs/extrinsic_json.h, outputs/summary_json.h
set(allowed
  api/result_json.h
  api/refine_checkpoint.h
  api/survey_ties.h
  config/config_json.h
  outputs/deviation_outputs.h
  outputs/extrinsic_json.h
  outputs/summary_json.h)
if(NOT ROOT)
  message(FATAL_ERROR "CheckHeadersWithoutJson: pass -DROOT=<source dir>")
endif()
include(${ROOT}/cmake/PublicHeaders.cmake)
set(offending)
foreach(h ${allowed})
  if("rvlio/${h}" IN_LIST rvlio_public_headers)
    list(APPEND offending "include/rvlio/${h} (public, yet listed as a JSON writer)")
  endif()
endforeach()
file(GLOB_RECURSE headers RELATIVE ${ROOT}/include/rvlio ${ROOT}/include/rvlio/*.h
  ${ROOT}/include/rvlio/*.hpp)
if(NOT headers)
  message(FATAL_ERROR "CheckHeadersWithoutJson: no headers under ${ROOT}/include/rvlio")
endif()
foreach(h ${headers})
  if(h IN_LIST allowed)
    continue()
  endif()
  file(STRINGS ${ROOT}/include/rvlio/${h} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]nlohmann/")
  if(lines)
    list(APPEND offending "include/rvlio/${h}")
  endif()
endforeach()
if(offending)
  list(JOIN offending ", " names)
  message(FATAL_ERROR "headers that include nlohmann/json (keep JSON in the I/O layer's "
                      "private writers, cmake/CheckHeadersWithoutJson.cmake): ${names}")
endif()
list(LENGTH headers n)
list(LENGTH rvlio_public_headers n_public)
message(STATUS "CheckHeadersWithoutJson: ${n} headers, none of the ${n_public} public ones "
               "includes nlohmann/json, nor any private one beyond the listed writers")
