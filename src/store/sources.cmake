set(FRAGG_STORE_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/block_codec.cpp
  ${CMAKE_CURRENT_LIST_DIR}/region_codec.cpp
  ${CMAKE_CURRENT_LIST_DIR}/region_record_store.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sqlite_page_store.cpp
  ${CMAKE_CURRENT_LIST_DIR}/lmdb_page_store.cpp
  ${CMAKE_CURRENT_LIST_DIR}/open_page_store.cpp
)
