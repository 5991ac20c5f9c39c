# ASan+UBSan for every target when RSU_SANITIZE is on (configure with -DRSU_SANITIZE=ON, Debug or
# RelWithDebInfo). Errors abort so that CTest reports them as failures.
if(RSU_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
  # Eigen 3.4 stops trusting malloc's 16-byte alignment when it sees __SANITIZE_ADDRESS__ and then frees
  # its heap blocks with its own "handmade" scheme, while the prebuilt (uninstrumented) PCL allocates
  # them with plain malloc: a PCL object built there and freed in our code (NDT's voxel leaves) is a
  # heap-buffer-overflow under ASan only. glibc's malloc (and ASan's) do return 16-byte-aligned blocks on
  # x86-64, so tell Eigen so and keep the same scheme as the libraries we link.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
endif()
