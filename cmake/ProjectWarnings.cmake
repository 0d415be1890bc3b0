# Warnings are a property of our own targets, never global flags:
# call libpd_set_warnings(target) on each target we compile. It also applies the sanitizers of
# LIBPD_SANITIZERS (cmake/Sanitizers.cmake), so that every target of ours is instrumented alike.
include(${CMAKE_CURRENT_LIST_DIR}/Sanitizers.cmake)

function(libpd_set_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>)
  libpd_set_sanitizers(${target})
endfunction()
