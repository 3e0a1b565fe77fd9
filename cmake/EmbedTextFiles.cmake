# sweepmap_embed_text_files(OUT FILES NAME_PART HEADER NAMESPACE FUNCTION COMMENT): a custom
# command that writes the C++ file OUT holding the text of FILES (see embed_text_files.cmake),
# rewritten when a file or the script changes.
set(SWEEPMAP_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_text_files.cmake)
function(sweepmap_embed_text_files)
  cmake_parse_arguments(E "" "OUT;NAME_PART;HEADER;NAMESPACE;FUNCTION;COMMENT" "FILES" ${ARGN})
  string(REPLACE ";" "," files_arg "${E_FILES}")  # one shell word
  add_custom_command(
    OUTPUT ${E_OUT}
    COMMAND ${CMAKE_COMMAND} -DOUT=${E_OUT} "-DSOURCES=${files_arg}" -DNAME_PART=${E_NAME_PART}
            -DHEADER=${E_HEADER} -DNAMESPACE=${E_NAMESPACE} -DFUNCTION=${E_FUNCTION}
            -P ${SWEEPMAP_EMBED_SCRIPT}
    DEPENDS ${E_FILES} ${SWEEPMAP_EMBED_SCRIPT}
    COMMENT "${E_COMMENT}")
endfunction()
