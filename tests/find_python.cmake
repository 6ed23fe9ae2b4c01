# Sets PYTHON for the end-to-end scripts: Debian's python3 (numpy, OpenCV: `make deps` installs
# them), since a python3 earlier on PATH may lack them.
find_program(PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT PYTHON)
  find_program(PYTHON NAMES python3)
endif()
