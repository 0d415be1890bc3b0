# Sanitizer builds (the `asan` presets, .ci/run-sanitizers): LIBPD_SANITIZERS is a list of
# sanitizers, e.g. "address;undefined", applied per target by libpd_set_sanitizers(target) (called
# from libpd_set_warnings, so every target of ours gets it), never through global flags.
set(LIBPD_SANITIZERS "" CACHE STRING
    "Sanitizers for every libpd target, a list of: address, undefined (empty: none)")

function(libpd_set_sanitizers target)
  if(NOT LIBPD_SANITIZERS)
    return()
  endif()
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "LIBPD_SANITIZERS needs GCC or Clang")
  endif()
  set(checks "")
  foreach(s IN LISTS LIBPD_SANITIZERS)
    if(s STREQUAL "address")
      list(APPEND checks address)
    elseif(s STREQUAL "undefined")
      # float-cast-overflow is not part of -fsanitize=undefined, but out-of-range double →
      # integer casts are exactly what absurd scene values (1e308 spacings) provoke.
      list(APPEND checks undefined float-cast-overflow)
    else()
      message(FATAL_ERROR "LIBPD_SANITIZERS: unknown sanitizer '${s}' (address, undefined)")
    endif()
  endforeach()
  list(JOIN checks "," joined)
  # Every finding stops the program, so a test that triggers one fails instead of printing.
  target_compile_options(${target} PRIVATE -fsanitize=${joined} -fno-sanitize-recover=all
                                           -fno-omit-frame-pointer)
  target_link_options(${target} PRIVATE -fsanitize=${joined})
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "STATIC_LIBRARY")
    # Whatever links the static library needs the runtime too (also targets that are not ours).
    target_link_options(${target} INTERFACE $<BUILD_INTERFACE:-fsanitize=${joined}>)
  endif()
endfunction()
