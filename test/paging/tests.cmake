# Out-of-core paging (issue 13): page stores (SQLite, LMDB), paged builds byte-identical to
# in-memory ones, queries and edits paging in, stores continued. Needs fragg_map_store.
if(TARGET fragg_map_store)
  fragg_add_test(fragg_paging_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/paging_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/state_masks_paging_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/paging_budget_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/paging_memory_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/region_reach_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/dynamic_paging_test.cpp
    LIBS fragg_map_store fragg_map_planning SQLite::SQLite3
    LABELS core paging)

  # Store formats: format 1 refused with the command that converts it, and converted.
  fragg_add_test(fragg_store_format_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/store_format_test.cpp
    LIBS fragg_map_store SQLite::SQLite3 ${ZSTD_LIBRARY} $<$<BOOL:${FRAGG_HAVE_LMDB}>:${LMDB_LIBRARY}>
    LABELS core paging)
  if(TARGET fragg_store_format_test)
    target_include_directories(fragg_store_format_test SYSTEM PRIVATE ${ZSTD_INCLUDE_DIR})
    if(FRAGG_HAVE_LMDB)
      target_include_directories(fragg_store_format_test SYSTEM PRIVATE ${LMDB_INCLUDE_DIR})
      target_compile_definitions(fragg_store_format_test PRIVATE FRAGG_TEST_LMDB=1)
    endif()
  endif()

  # kill -9 of `fragg_map build --page-store` at several moments; the store read meanwhile.
  fragg_add_test(cli_store_crash_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/store_crash_test.cpp
    LIBS fragg_map_store
    LABELS cli paging)
  if(TARGET cli_store_crash_test)
    add_dependencies(cli_store_crash_test fragg_map_cli)
    target_compile_definitions(cli_store_crash_test PRIVATE
      FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
  endif()
endif()
