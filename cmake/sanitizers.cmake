# ASan+UBSan for every target when RSU_SANITIZE is on (configure with -DRSU_SANITIZE=ON, Debug or
# RelWithDebInfo). Errors abort so that CTest reports them as failures.
if(RSU_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()
