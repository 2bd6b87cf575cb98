# Warnings as an interface target: every Luxel target links luxel_warnings.
add_library(luxel_warnings INTERFACE)
target_compile_options(luxel_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align
  -Wunused -Woverloaded-virtual -Wnull-dereference
  -Wimplicit-fallthrough
  $<$<BOOL:${LUXEL_WERROR}>:-Werror>)

# Sanitizer build (ASan + UBSan) as an option; exercised by test.sh --sanitize.
add_library(luxel_sanitizers INTERFACE)
if(LUXEL_SANITIZE)
  target_compile_options(luxel_sanitizers INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(luxel_sanitizers INTERFACE -fsanitize=address,undefined)
endif()
