# Warnings live on an interface target that every sflsh target links privately.
if(TARGET sflsh_warnings)
  return()
endif()
add_library(sflsh_warnings INTERFACE)
target_compile_options(sflsh_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual
  -Wdouble-promotion -Wimplicit-fallthrough)
if(SFLSH_WERROR)
  target_compile_options(sflsh_warnings INTERFACE -Werror)
endif()
# A unity build includes every source into a generated file, so GCC takes each for a header and warns about a
# class that holds a type of the file's anonymous namespace (a Pimpl's helpers): harmless here, the batch is still
# one translation unit.
if(SFLSH_UNITY)
  target_compile_options(sflsh_warnings INTERFACE -Wno-subobject-linkage)
endif()
