# The test Python.pip_install: `pip install .` offline into a fresh venv that sees Debian's
# packages (python3 -m venv --system-site-packages), then physgrad imported from that venv — not
# from the build tree — and an example run with it. The package's files are copied to WORK/src,
# so that nothing is written into the source tree; setup.py reuses the configured build tree
# BUILD (PHYSGRAD_CMAKE_BUILD_DIR), so the install compiles nothing already built.
# cmake -DPYTHON=… -DSOURCE=… -DBUILD=… -DWORK=… -DEXAMPLE=… -P pip_install_test.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/src/python)
foreach(file pyproject.toml setup.py CMakeLists.txt README.md)
  file(COPY ${SOURCE}/${file} DESTINATION ${WORK}/src)
endforeach()
file(COPY ${SOURCE}/python/physgrad DESTINATION ${WORK}/src/python
     PATTERN __pycache__ EXCLUDE)

# (No ';' in an argument: ARGN would split it.)
function(run what)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${WORK} RESULT_VARIABLE status
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

run("python3 -m venv --system-site-packages" ${PYTHON} -m venv --system-site-packages ${WORK}/venv)
# No index and no other place to fetch from: what the install needs must be here already.
run("pip install --no-build-isolation --no-index ."
    ${CMAKE_COMMAND} -E env --unset=PIP_FIND_LINKS --unset=PYTHONPATH PIP_NO_INDEX=1
    PIP_CONFIG_FILE=/dev/null PHYSGRAD_CMAKE_BUILD_DIR=${BUILD}
    ${WORK}/venv/bin/python -m pip install --no-build-isolation --no-index --no-cache-dir
    ${WORK}/src)
run("import physgrad from the venv"
    ${CMAKE_COMMAND} -E env --unset=PYTHONPATH ${WORK}/venv/bin/python -c
    "import pathlib, physgrad, physgrad.torch\np = pathlib.Path(physgrad.__file__).parent\nprint(p, physgrad.__version__, (p / 'py.typed').exists(), (p / '_physgrad.pyi').exists())")
string(STRIP "${output}" output)
if(NOT output MATCHES "^${WORK}/venv/lib/python[0-9.]+/site-packages/physgrad [0-9.]+ True True$")
  message(FATAL_ERROR "physgrad was not imported from the venv with its stubs: ${output}")
endif()
message(STATUS "installed: ${output}")
run("the example ${EXAMPLE}" ${CMAKE_COMMAND} -E env --unset=PYTHONPATH
    ${WORK}/venv/bin/python ${EXAMPLE} --quick)
message(STATUS "${output}")
