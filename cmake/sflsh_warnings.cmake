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
