# Project-wide warning flags, applied per target with rsu_warnings(target).
function(rsu_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wold-style-cast -Wcast-align -Woverloaded-virtual
                                           -Wdouble-promotion -Wformat=2)
  if(RSU_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
