# sflsh_add_library(NAME SOURCES <files> [PUBLIC <deps>] [PRIVATE <deps>] [PRIVATE_HEADERS] [NO_INCLUDE]): one of the
# project's libraries, sflsh_NAME with its alias sflsh::NAME, its precompiled headers (sflsh_pch.cmake), the folder's
# include/ as its public include directory (not with NO_INCLUDE: a library sharing another's headers), src/ as a
# private one with PRIVATE_HEADERS (private headers included by room, "room/x.hpp"), and the project's warnings.
function(sflsh_add_library name)
  cmake_parse_arguments(ARG "PRIVATE_HEADERS;NO_INCLUDE" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  set(target sflsh_${name})
  add_library(${target} ${ARG_SOURCES})
  sflsh_precompile(${target})
  add_library(sflsh::${name} ALIAS ${target})
  if(NOT ARG_NO_INCLUDE)
    target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  endif()
  if(ARG_PRIVATE_HEADERS)
    target_include_directories(${target} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  endif()
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC} PRIVATE sflsh_warnings ${ARG_PRIVATE})
endfunction()
