# cmake -DPYTHON=/usr/bin/python3 -DAPP=perishell -DROOT=<source> -DWORK=<dir> -P render_3d_check.cmake
# perf/charts/render_results.py on the `perishell check --output` models of a curved shell (the
# hinged roof, 64 quads, its rise 5 % of its span) and a flat plate (gmsh_plate, 8 quads):
# --view auto draws the roof in 3-D (the same PNG as --view 3d) and the plate as its x-y
# projection (the same PNG as --view xy, as before 3-D views existed); the camera options
# change the picture; a bad --view or angle is a one-line error with exit status 1.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(script "${ROOT}/perf/charts/render_results.py")

foreach(model "roof;${ROOT}/tests/data/decks/run/hinged_roof_arc_length.yaml"
              "plate;${ROOT}/tests/data/decks/gmsh_plate.yaml")
  list(GET model 0 name)
  list(GET model 1 deck)
  execute_process(COMMAND "${APP}" check "${deck}" --output "${WORK}/${name}"
                  RESULT_VARIABLE exit_code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT exit_code EQUAL 0 OR NOT EXISTS "${WORK}/${name}/model.xmf")
    message(FATAL_ERROR "perishell check ${deck} exited ${exit_code}:\n${out}\n${err}")
  endif()
endforeach()

# render(<out prefix> <model> <options>...): runs the script, expects exit 0 and the PNG.
function(render prefix model)
  execute_process(COMMAND "${PYTHON}" "${script}" damage "${WORK}/${model}/model.xmf" --field bonds
                          --dpi 80 --out "${WORK}/${prefix}" ${ARGN}
                  RESULT_VARIABLE exit_code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(png "${WORK}/${prefix}_bonds_0ns.png")
  if(NOT exit_code EQUAL 0 OR NOT EXISTS "${png}")
    message(FATAL_ERROR "render_results.py ${model} ${ARGN} exited ${exit_code}:\n${out}\n${err}")
  endif()
  file(SIZE "${png}" size)
  if(size LESS 8000)  # a blank figure is about 2 kB; these are 15-40 kB
    message(FATAL_ERROR "${png}: ${size} bytes, too small to hold a drawing")
  endif()
  file(SHA256 "${png}" hash)
  set(${prefix}_hash "${hash}" PARENT_SCOPE)
endfunction()

render(roof_auto roof)
render(roof_3d roof --view 3d)
render(roof_camera roof --view 3d --elev 60 --azim 30 --shading flat)
render(plate_auto plate)
render(plate_xy plate --view xy)
if(NOT roof_auto_hash STREQUAL roof_3d_hash)
  message(FATAL_ERROR "--view auto did not draw the curved roof in 3-D (its PNG differs from --view 3d's)")
endif()
if(roof_camera_hash STREQUAL roof_3d_hash)
  message(FATAL_ERROR "--elev/--azim/--shading did not change the 3-D picture")
endif()
if(NOT plate_auto_hash STREQUAL plate_xy_hash)
  message(FATAL_ERROR "--view auto did not draw the flat plate as its x-y projection")
endif()

foreach(case "roof;--view 4d;argument --view: invalid choice: '4d'"
             "roof;--elev 91;argument --elev: 91 degrees is outside \\[-90, 90\\]"
             "roof;--azim nan;argument --azim: 'nan' is not finite"
             "plate;--view xy --elev 10;--elev/--azim set the 3-D camera, but --view xy draws a 2-D projection")
  list(GET case 0 model)
  list(GET case 1 options)
  list(GET case 2 expected)
  separate_arguments(options)
  execute_process(COMMAND "${PYTHON}" "${script}" damage "${WORK}/${model}/model.xmf" --out "${WORK}/bad" ${options}
                  RESULT_VARIABLE exit_code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT exit_code EQUAL 1 OR NOT err MATCHES "render_results: error: ${expected}")
    message(FATAL_ERROR "${options}: expected exit 1 and '${expected}', got ${exit_code}:\n${out}\n${err}")
  endif()
endforeach()
message(STATUS "render_results.py 3-D view: OK")
