# The layers of core/, bottom first. A layer's files may include their own layer and the layers
# listed before it, never one after it: cmake/check_layers.cmake enforces it on every build.
#   util        formatting and timing helpers, the Eigen decompositions compiled once (Eigen only)
#   geometry    conventions, the camera model, small value types (ids, axes, segments)
#   optim       the Levenberg-Marquardt driver, the damped Schur step, the shape of solver summaries
#   mesh        the half-edge mesh, K-operators, primitives, extrusion, triangulation
#   image       photo decoding and EXIF
#   estimators  calibration: vanishing points, DLT, plumb line, two-view, homography,
#               projective upgrade, self-calibration (the paper's plane image processing)
#   scene       the project (K, F) and the undoable document
#   solve       scene and joint solve, constraint polish, vertex moves, multi-view
#               initialisation, the model update after an edit (the paper's optimisation)
#   texture     the texture bake
#   io          the project file, the CLI's JSON, exports
set(FACET_CORE_LAYERS util geometry optim mesh image estimators scene solve texture io)
