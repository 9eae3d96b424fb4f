// sarmap-viewer-demo: serves the viewer page on a synthetic scene (no robot, no LCM), for UI
// work and the headless-browser test.
#include <unistd.h>

#include <cstdio>

#include "common/args.h"
#include "viewer/demo_scene.h"
#include "viewer/viewer_server.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-viewer-demo", [&] {
    sarmap::common::ArgParser parser("sarmap-viewer-demo",
                                     "Serves the viewer on a synthetic scene.");
    int port = 0;
    double seconds = 30;
    std::string token;
    bool hostile = false;
    parser.AddFlag("--port", &port, "port (0: any free one, printed)");
    parser.AddFlag("--seconds", &seconds, "how long to serve");
    parser.AddFlag("--token", &token, "access token to require");
    parser.AddSwitch("--hostile", &hostile,
                     "names and keywords holding HTML and script (escaping test)");
    if (!parser.Parse(argc, argv)) return 0;
    sarmap::viewer::ViewerState state;
    sarmap::viewer::FillDemoScene(&state);
    if (hostile) sarmap::viewer::AddHostileStrings(&state);
    sarmap::viewer::ViewerServer server(&state, {"127.0.0.1", port, token});
    server.Start();
    printf("port %d\n", server.port());
    fflush(stdout);
    // Refresh like a live robot would (the launcher reports every second).
    for (double t = 0; t < seconds; t += 0.5) {
      usleep(500000);
      sarmap::viewer::FillDemoScene(&state);
      if (hostile) sarmap::viewer::AddHostileStrings(&state);
    }
    return 0;
  });
}
