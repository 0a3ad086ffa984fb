# The worker pool of the occlusion study and the NBV scorer (src/parallel_for.h, header only).
semioctree_add_test(test_parallel_for SOURCES test_parallel_for.cpp)
target_include_directories(test_parallel_for PRIVATE ${PROJECT_SOURCE_DIR})
