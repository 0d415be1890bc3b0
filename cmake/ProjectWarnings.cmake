# Warnings are a property of our own targets, never global flags:
# call libpd_set_warnings(target) on each target we compile.
function(libpd_set_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>)
endfunction()
