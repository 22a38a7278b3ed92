# nbv_embed_files(<target> HEADER <header> NAMESPACE <ns> CONSTANTS <constant>... FILES <file>...):
# each file's bytes, read at build time, as a `const std::string_view <constant>` (the constants
# in the files' order) in namespace <ns>, compiled into <target>. <header> (as the target
# includes it) declares the constants. A file that changes is embedded again at the next build.
# Run as a script (cmake -P), this file writes the source.

if(CMAKE_SCRIPT_MODE_FILE)
  string(REPLACE "|" ";" constants "${CONSTANTS}")
  string(REPLACE "|" ";" files "${FILES}")
  set(text "// Generated at build time by cmake/NbvEmbed.cmake: edit the files it embeds instead.\n")
  string(APPEND text "#include \"${HEADER}\"\n\nnamespace ${NAMESPACE} {\n")
  foreach(constant file IN ZIP_LISTS constants files)
    file(READ "${file}" content)
    string(FIND "${content}" ")nbv_embed\"" clash)
    if(NOT clash EQUAL -1)
      message(FATAL_ERROR "${file} holds the text ')nbv_embed\"', which ends the raw string it is embedded in")
    endif()
    string(APPEND text "\nconst std::string_view ${constant} = R\"nbv_embed(${content})nbv_embed\";\n")
  endforeach()
  string(APPEND text "\n}  // namespace ${NAMESPACE}\n")
  file(WRITE "${OUTPUT}.tmp" "${text}")
  file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
  return()
endif()

set(NBV_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_FILE})

function(nbv_embed_files target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "HEADER;NAMESPACE" "CONSTANTS;FILES")
  list(LENGTH arg_CONSTANTS constant_count)
  list(LENGTH arg_FILES file_count)
  if(NOT constant_count EQUAL file_count)
    message(FATAL_ERROR "nbv_embed_files: ${constant_count} constants for ${file_count} files")
  endif()
  list(TRANSFORM arg_FILES PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/ REGEX "^[^/]")
  list(JOIN arg_CONSTANTS "|" constants)
  list(JOIN arg_FILES "|" files)
  string(MAKE_C_IDENTIFIER "${arg_HEADER}" stem)
  set(output ${CMAKE_CURRENT_BINARY_DIR}/embedded_${stem}.cpp)
  add_custom_command(
    OUTPUT ${output}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${output} -DHEADER=${arg_HEADER} -DNAMESPACE=${arg_NAMESPACE}
            -DCONSTANTS=${constants} -DFILES=${files} -P ${NBV_EMBED_SCRIPT}
    DEPENDS ${arg_FILES} ${NBV_EMBED_SCRIPT}
    COMMENT "Embedding ${arg_HEADER}'s files"
    VERBATIM)
  target_sources(${target} PRIVATE ${output})
endfunction()
