# The layers of app/, bottom first. A layer's files may include their own layer, the layers
# listed before it and core/, never a layer after it: cmake/check_layers.cmake (-DTREE=app) enforces it on
# every build.
#   platform  the GL side without app state: the EGL context and offscreen target, GL
#             helpers, the shaders, tiled photo textures, and gl_camera.h (the one place
#             that converts between core's Eigen cameras and GLM's GL matrices)
#   state     what the app knows between frames that is not the document's: AppState,
#             selection, the edit functions (commands), picking, the Move tool's drag, the
#             orbit camera, the input script, adding photos
#   panels    what draws into an ImGui window and turns input into edits: the image panel
#             (view, overlays, loupe), the 3D viewport, the properties sections, the side
#             panels and the shared widgets; each panel's own UI state lives in a struct
#   shell     the frame (layout, splitters, dialogs, menu bar), the window and offscreen
#             modes, the command line and main()
set(FACET_APP_LAYERS platform state panels shell)
