# The install layout's relative steps between directories, for a relocatable install: nothing
# below depends on CMAKE_INSTALL_PREFIX, so the installed tree works wherever it is moved.
#   COMBABC_DATA_FROM_BINDIR     bin/ -> share/combabc   (the CLI finds the report script)
#   COMBABC_DATA_FROM_LIBDIR     lib/ -> share/combabc   (a shared libcombabc)
#   COMBABC_DATA_FROM_PYTHONDIR  <python dir>/combabc -> share/combabc (the Python module)
#   COMBABC_LIB_FROM_BINDIR, COMBABC_LIB_FROM_PYTHONDIR: the RPATHs of a shared build
#   COMBABC_PREFIX_FROM_PKGCONFIG: lib/pkgconfig -> the prefix (combabc.pc)
# A directory given as an absolute path has no relative step: its entry is empty (not relocatable).
set(layout_root /combabc-prefix)  # any absolute path: only the differences matter
function(combabc_relative out from to)
  foreach(dir from to)
    if(IS_ABSOLUTE "${${dir}}")
      set(${out} "" PARENT_SCOPE)
      return()
    endif()
  endforeach()
  file(RELATIVE_PATH step ${layout_root}/${from} ${layout_root}/${to})
  if(step STREQUAL "")
    set(step ".")
  endif()
  set(${out} "${step}" PARENT_SCOPE)
endfunction()
set(combabc_data_dir ${CMAKE_INSTALL_DATADIR}/combabc)
combabc_relative(COMBABC_DATA_FROM_BINDIR "${CMAKE_INSTALL_BINDIR}" "${combabc_data_dir}")
combabc_relative(COMBABC_DATA_FROM_LIBDIR "${CMAKE_INSTALL_LIBDIR}" "${combabc_data_dir}")
combabc_relative(COMBABC_DATA_FROM_PYTHONDIR "${COMBABC_PYTHON_INSTALL_DIR}/combabc"
  "${combabc_data_dir}")
combabc_relative(COMBABC_LIB_FROM_BINDIR "${CMAKE_INSTALL_BINDIR}" "${CMAKE_INSTALL_LIBDIR}")
combabc_relative(COMBABC_LIB_FROM_PYTHONDIR "${COMBABC_PYTHON_INSTALL_DIR}/combabc"
  "${CMAKE_INSTALL_LIBDIR}")
combabc_relative(COMBABC_PREFIX_FROM_PKGCONFIG "${CMAKE_INSTALL_LIBDIR}/pkgconfig" ".")
if(COMBABC_SHARED)
  set(COMBABC_LIBRARY_KIND SHARED)
else()
  set(COMBABC_LIBRARY_KIND STATIC)
endif()
message(STATUS "combabc: ${COMBABC_LIBRARY_KIND} libraries")
