# Warnings and sanitizers, applied per target so that third-party headers stay quiet.
if(COMBABC_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

function(combabc_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual)
  if(COMBABC_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
