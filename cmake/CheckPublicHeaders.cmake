# `cmake -DSOURCE_DIR=<repo> -P cmake/CheckPublicHeaders.cmake`: every
# rvlio/... header that a public header (cmake/PublicHeaders.cmake) includes
# is itself on the list, so the installed headers compile from the prefix.
# A cheap ctest (PublicHeadersClosed) in front of scripts/install_test.sh,
# which compiles each installed header but runs only in the install stage.
include(${SOURCE_DIR}/cmake/PublicHeaders.cmake)
set(missing "")
foreach(header ${rvlio_public_headers})
  set(path ${SOURCE_DIR}/include/${header})
  if(NOT EXISTS ${path})
    list(APPEND missing "${header} (listed, but include/${header} does not exist)")
    continue()
  endif()
  file(STRINGS ${path} include_lines REGEX "^#include \"rvlio/")
  foreach(line ${include_lines})
    string(REGEX REPLACE "^#include \"(rvlio/[^\"]+)\".*" "\\1" included "${line}")
    if(included STREQUAL "rvlio/version.h")
      continue()  # generated, installed beside the list
    endif()
    list(FIND rvlio_public_headers ${included} index)
    if(index EQUAL -1)
      list(APPEND missing "${included} (included by ${header})")
    endif()
  endforeach()
endforeach()
if(missing)
  list(JOIN missing "\n  " text)
  message(FATAL_ERROR "cmake/PublicHeaders.cmake is not closed under #include; add:\n  ${text}")
endif()
list(LENGTH rvlio_public_headers count)
message(STATUS "the ${count} public headers include only public headers")
