# Next-Best-View candidates, scores and the stop percentage (src/nbv/, docs/nbv.md).
semioctree_add_test(test_nbv_scoring SOURCES test_nbv_scoring.cpp LIBS semioctree)
# (and the project's root: the walls' shadows, src/nbv/wall_shadows.h, are tested directly)
target_include_directories(test_nbv_scoring PRIVATE ${CMAKE_CURRENT_SOURCE_DIR} ${PROJECT_SOURCE_DIR})
semioctree_add_test(test_nbv_candidates SOURCES test_nbv_candidates.cpp LIBS semioctree)
target_include_directories(test_nbv_candidates PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
semioctree_add_test(test_nbv_overlap SOURCES test_nbv_overlap.cpp LIBS semioctree)
target_include_directories(test_nbv_overlap PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
semioctree_add_test(test_nbv_rooms SOURCES test_nbv_rooms.cpp LIBS semioctree)
target_include_directories(test_nbv_rooms PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
semioctree_add_test(test_nbv SOURCES test_nbv.cpp LIBS semioctree)
target_include_directories(test_nbv PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
# The lab tests need the synthetic scanner for their input.
if(TARGET semioctree_sim)
  target_link_libraries(test_nbv PRIVATE semioctree_sim)
  target_compile_definitions(test_nbv PRIVATE SEMIOCTREE_HAVE_SIM=1)
  semioctree_add_bench(bench_nbv SOURCES bench_nbv.cpp LIBS semioctree_sim_platform)
endif()
# map-nbv on maps built as OctoMap users build them (sparse scans of generated and built-in
# scenes along a path, insertPointCloud, the floor shifted), judged against the scenes.
if(TARGET semioctree_sim_platform)
  semioctree_add_test(test_map_nbv_user_maps SOURCES test_map_nbv_user_maps.cpp
                      LIBS semioctree_sim_platform nlohmann_json::nlohmann_json)
  target_include_directories(test_map_nbv_user_maps PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  add_dependencies(test_map_nbv_user_maps semioctree_cli)
endif()
