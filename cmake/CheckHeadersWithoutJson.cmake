# No header of include/rvlio includes nlohmann/json: JSON is the I/O layer's
# way of writing summary.json and chunk.json, not part of the estimators'
# interface. Run by CTest (test HeadersWithoutJson):
#   cmake -DROOT=<source dir> -P cmake/CheckHeadersWithoutJson.cmake
# Fails naming every offending header.
cmake_minimum_required(VERSION 3.16)  # if(IN_LIST)
#
# The exceptions, all of the I/O layer (rvlio_io), which builds its JSON in
# them; each is to leave this list when its JSON moves into src/:
#   api.h                  RunResult/RefineResult::summary, RunArgs::annotate_summary
#   api/refine_checkpoint.h, api/survey_ties.h   summary.json pieces of refine and merge
#   config/config.h        ToJson, the resolved configuration of summary.json
#   outputs/deviation_outputs.h, outputs/extrinsic_json.h, outputs/summary_json.h
set(allowed
  api.h
  api/refine_checkpoint.h
  api/survey_ties.h
  config/config.h
  outputs/deviation_outputs.h
  outputs/extrinsic_json.h
  outputs/summary_json.h)
if(NOT ROOT)
  message(FATAL_ERROR "CheckHeadersWithoutJson: pass -DROOT=<source dir>")
endif()
file(GLOB_RECURSE headers RELATIVE ${ROOT}/include/rvlio ${ROOT}/include/rvlio/*.h
  ${ROOT}/include/rvlio/*.hpp)
if(NOT headers)
  message(FATAL_ERROR "CheckHeadersWithoutJson: no headers under ${ROOT}/include/rvlio")
endif()
set(offending)
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
  message(FATAL_ERROR "headers that include nlohmann/json (keep JSON in src/, "
                      "cmake/CheckHeadersWithoutJson.cmake): ${names}")
endif()
list(LENGTH headers n)
message(STATUS "CheckHeadersWithoutJson: ${n} headers, none includes nlohmann/json beyond the listed exceptions")
