# Reads ESP-IDF components' CMakeLists.txt in script mode (cmake -P) and writes, for each one, the
# public include folders and public requirements it registers, so that the firmware check takes
# its include path from ESP-IDF's own component definitions instead of a hand-kept list.
#
#   cmake -DIDF_PATH=... -DIDF_TARGET=esp32s3 -DSDKCONFIG_CMAKE=.../sdkconfig.cmake
#         -DCOMPONENTS="a;b;c" -DOUTPUT=components.txt -P components.cmake
#
# Script mode runs the components' logic (their `if(CONFIG_...)` choices, target and architecture
# folders) for real; the commands that only make sense while generating a build (targets, custom
# commands, linker scripts) are defined here as no-ops, and idf_component_register records its
# arguments. OUTPUT gets one line per component: NAME|include;dirs|requires.
cmake_minimum_required(VERSION 3.16)

include(${SDKCONFIG_CMAKE})
include(${IDF_PATH}/tools/cmake/utilities.cmake)  # spaces2list and friends, ESP-IDF's own
if(CONFIG_IDF_TARGET_ARCH_XTENSA)
    set(IDF_TARGET_ARCH xtensa)
endif()
set(target ${IDF_TARGET})
set(idf_target ${IDF_TARGET})
set(BOOTLOADER_BUILD 0)
set(CMAKE_C_COMPILER_ID GNU)
set(CMAKE_SYSTEM_NAME Generic)
file(WRITE ${OUTPUT} "")

# The build properties a component's CMakeLists reads; any other reads as empty.
set(_property_IDF_TARGET ${IDF_TARGET})
set(_property_IDF_PATH ${IDF_PATH})
set(_property_IDF_TARGET_ARCH ${IDF_TARGET_ARCH})
set(_property_COMPONENTS ${COMPONENTS})
set(_property_BUILD_COMPONENTS ${COMPONENTS})
set(_property_BUILD_DIR ${CMAKE_CURRENT_BINARY_DIR})
set(_property_IDF_VER "v5.5.4")

function(idf_build_get_property var property)
    set(${var} "${_property_${property}}" PARENT_SCOPE)
endfunction()

function(idf_component_register)
    cmake_parse_arguments(arg "WHOLE_ARCHIVE"
        "KCONFIG;KCONFIG_PROJBUILD"
        "SRCS;SRC_DIRS;EXCLUDE_SRCS;INCLUDE_DIRS;PRIV_INCLUDE_DIRS;LDFRAGMENTS;REQUIRES;PRIV_REQUIRES;REQUIRED_IDF_TARGETS;EMBED_FILES;EMBED_TXTFILES"
        ${ARGN})
    set(dirs "")
    foreach(dir ${arg_INCLUDE_DIRS})
        get_filename_component(abs ${dir} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_LIST_DIR})
        list(APPEND dirs ${abs})
    endforeach()
    file(APPEND ${OUTPUT} "${COMPONENT_NAME}|${dirs}|${arg_REQUIRES}\n")
endfunction()

# Everything else a component's CMakeLists may call: nothing to record for the include path.
foreach(command
        target_link_libraries target_compile_definitions target_compile_options target_sources
        target_include_directories target_link_options target_link_directories target_linker_script
        set_source_files_properties add_dependencies add_custom_target add_custom_command
        add_prebuilt_library add_subdirectory add_library add_deprecated_target_alias
        set_target_properties include_directories idf_component_get_property
        idf_component_set_property idf_component_optional_requires idf_build_set_property
        rom_linker_script esptool_py_flash_target_image esptool_py_flash_target esptool_py_custom_target
        partition_table_get_partition_info partition_table_add_check_bootloader_size_target
        partition_table_add_check_size_target target_add_binary_data fail_at_build_time
        mbedcrypto_optional_deps file_generate get_target_property add_prefix find_library
        find_package execute_process set_property spiffs_create_partition_image
        fatfs_create_spiflash_image idf_build_component)
    cmake_language(EVAL CODE "function(${command})\nendfunction()")
endforeach()

function(read_component name)
    set(COMPONENT_NAME ${name})
    set(COMPONENT_DIR ${IDF_PATH}/components/${name})
    set(COMPONENT_LIB __idf_${name})
    set(COMPONENT_TARGET __idf_${name})
    set(CMAKE_CURRENT_SOURCE_DIR ${COMPONENT_DIR})
    if(EXISTS ${COMPONENT_DIR}/CMakeLists.txt)
        include(${COMPONENT_DIR}/CMakeLists.txt)
    endif()
endfunction()

foreach(name ${COMPONENTS})
    read_component(${name})
endforeach()
