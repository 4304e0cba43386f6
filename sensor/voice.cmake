# Voice commands (the Kinect carries the microphones, so they live in sensor/): keyword spotting with
# pocketsphinx. Included from sensor/CMakeLists.txt; owned by the filter-and-voice issue.
find_package(PkgConfig REQUIRED)
# Debian's sphinxbase.pc names /usr/include/sphinxbase, which does not exist (the headers are under the
# multiarch include dir), and CMake refuses imported targets with missing include paths: build the
# target by hand from the existing directories.
pkg_check_modules(POCKETSPHINX REQUIRED pocketsphinx sphinxbase)
set(TACHI_POCKETSPHINX_INCLUDE_DIRS "")
foreach(dir IN LISTS POCKETSPHINX_INCLUDE_DIRS)
  if(EXISTS "${dir}")
    list(APPEND TACHI_POCKETSPHINX_INCLUDE_DIRS "${dir}")
  endif()
endforeach()
if(NOT TARGET tachi_pocketsphinx)
  add_library(tachi_pocketsphinx INTERFACE)
  target_include_directories(tachi_pocketsphinx SYSTEM INTERFACE ${TACHI_POCKETSPHINX_INCLUDE_DIRS})
  target_link_libraries(tachi_pocketsphinx INTERFACE ${POCKETSPHINX_LINK_LIBRARIES})
endif()
if(NOT TARGET PkgConfig::FREENECT)
  pkg_check_modules(FREENECT REQUIRED IMPORTED_TARGET libfreenect)
endif()

add_library(tachi_voice STATIC
  src/voice_commands.cpp
  src/voice_audio.cpp
  src/voice_devices.cpp
  src/voice_spotter.cpp)
add_library(tachi::voice ALIAS tachi_voice)
target_include_directories(tachi_voice PUBLIC include)
target_link_libraries(tachi_voice
  PRIVATE tachi_pocketsphinx PkgConfig::FREENECT nlohmann_json::nlohmann_json tachi::common tachi_warnings)

# The stage on the bus (VoiceNode, src/voice_node.cpp) and the thin executable (voice_cli.cpp: flags).
add_library(tachi_voice_node STATIC src/voice_node.cpp)
target_include_directories(tachi_voice_node PUBLIC include)
target_link_libraries(tachi_voice_node PUBLIC tachi_voice
  PRIVATE tachi_sensor_bus tachi::bus tachi::common spdlog::spdlog tachi_warnings)
add_library(tachi_voice_cli STATIC voice_cli.cpp)
target_include_directories(tachi_voice_cli PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(tachi_voice_cli PUBLIC tachi_voice_node tachi::voice tachi_sensor_node tachi::common PRIVATE tachi_warnings)
add_executable(tachi-voice voice_main.cpp)
target_link_libraries(tachi-voice PRIVATE tachi_voice_cli tachi_voice_node tachi::voice tachi::bus tachi::common spdlog::spdlog tachi_warnings)
