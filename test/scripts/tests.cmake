# Scripts: install_deps.sh's wait for a held apt/dpkg lock (sourced; installs nothing).
fragg_add_test(scripts_install_deps_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/install_deps_lock_test.cpp
  LABELS scripts)
if(TARGET scripts_install_deps_test)
  target_compile_definitions(scripts_install_deps_test PRIVATE
    FRAGG_INSTALL_DEPS="${PROJECT_SOURCE_DIR}/scripts/install_deps.sh")
endif()
