# Tests of the registration stage (include/semioctree/registration.h). The lab
# acceptance test needs the synthetic scanner; without it only the analytic tests build.
if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/test_registration.cpp)
  if(TARGET semioctree_sim)
    semioctree_add_test(test_registration SOURCES test_registration.cpp LIBS semioctree semioctree_sim)
    target_compile_definitions(test_registration PRIVATE SEMIOCTREE_HAVE_SIM=1)
  else()
    semioctree_add_test(test_registration SOURCES test_registration.cpp LIBS semioctree)
  endif()
  # ${PROJECT_SOURCE_DIR}: ICP's planar step (src/planar_point_to_plane.h, header only).
  target_include_directories(test_registration PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}
                                                       ${PROJECT_SOURCE_DIR})
endif()
# The kd-tree of registration (src/kd_tree_n.h, header only, over nanoflann).
semioctree_add_test(test_kd_tree SOURCES test_kd_tree.cpp LIBS semioctree)
target_include_directories(test_kd_tree PRIVATE ${PROJECT_SOURCE_DIR})
target_link_libraries(test_kd_tree PRIVATE nanoflann::nanoflann)
# Registration without a pose over lab pairs and the real scan's moved copy (JSON).
if(TARGET semioctree_sim)
  semioctree_add_bench(bench_global_registration SOURCES bench_global_registration.cpp
                       LIBS semioctree semioctree_sim nlohmann_json::nlohmann_json)
  if(TARGET bench_global_registration)
    target_include_directories(bench_global_registration PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  endif()
endif()
# Registration without a pose; its lab pairs need the synthetic scanner.
if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/test_global_registration.cpp)
  if(TARGET semioctree_sim)
    semioctree_add_test(test_global_registration SOURCES test_global_registration.cpp
                        LIBS semioctree semioctree_sim COST 180)
    target_compile_definitions(test_global_registration PRIVATE SEMIOCTREE_HAVE_SIM=1)
  else()
    semioctree_add_test(test_global_registration SOURCES test_global_registration.cpp
                        LIBS semioctree)
  endif()
  target_include_directories(test_global_registration PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endif()
