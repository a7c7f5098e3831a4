# Writes OUT (a header defining CTK_GIT_DESCRIBE) from `git describe` of SOURCE_DIR, touching it
# only when the description changed, so that a build names the commit it was built from.
execute_process(COMMAND git -C "${SOURCE_DIR}" describe --always --dirty --tags
                OUTPUT_VARIABLE described OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
if(failed OR described STREQUAL "")
  set(described "not built from a git checkout")
endif()
file(WRITE "${OUT}.new" "#define CTK_GIT_DESCRIBE \"${described}\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUT}.new" "${OUT}")
file(REMOVE "${OUT}.new")
