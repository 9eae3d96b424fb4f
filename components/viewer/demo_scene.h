#pragma once
// A synthetic scene for the viewer: a walled room, a trail, a scan, people of every cue and
// sound sources. Used by the tests and by sarmap-viewer-demo (UI work without a robot).

#include "viewer/viewer_state.h"

namespace sarmap {
namespace viewer {

inline void FillDemoScene(ViewerState* state) {
  GridImage grid;
  grid.resolution_m = 0.05;
  grid.width = 160;
  grid.height = 120;
  grid.origin_x_m = -1;
  grid.origin_y_m = -1;
  grid.cells.assign(grid.width * grid.height, -1);
  for (int y = 10; y < 110; ++y)
    for (int x = 10; x < 150; ++x)
      grid.cells[y * grid.width + x] =
          (y == 10 || y == 109 || x == 10 || x == 149 || (x == 80 && y < 70)) ? 100 : 0;
  state->SetMap(grid);
  for (int i = 0; i <= 40; ++i)
    state->SetPose(1'000'000 + i * 100'000, 0.5 + i * 0.1, 1.0 + 0.02 * i, 0.1);
  std::vector<Eigen::Vector2d> scan;
  for (int i = 0; i < 40; ++i) scan.emplace_back(6.4, 0.5 + i * 0.08);
  state->SetScan(scan);
  PersonView seen{1,   5.0,  3.2,   ThreeSigmaEllipse(Eigen::Matrix2d::Identity() * 0.01),
                  0.9, true, false, false,
                  1,   ""};
  PersonView heard{
      2,     2.0,
      4.2,   ThreeSigmaEllipse((Eigen::Matrix2d() << 0.09, 0.03, 0.03, 0.04).finished()),
      0.7,   false,
      false, true,
      1,     "help"};
  PersonView both{3,    5.6,   1.0,   ThreeSigmaEllipse(Eigen::Matrix2d::Identity() * 0.02),
                  0.95, true,  false, true,
                  2,    "here"};
  state->SetPeople({seen, heard, both});
  SourceView phone{11,          3.0,  1.5, ThreeSigmaEllipse(Eigen::Matrix2d::Identity() * 0.04),
                   "converged", false};
  SourceView voice{
      12,          2.0,
      4.2,         ThreeSigmaEllipse((Eigen::Matrix2d() << 0.09, 0.03, 0.03, 0.04).finished()),
      "converged", true};
  state->SetSources({phone, voice});
  ProcessView slam{"", "sarmap-slam", "running", 1234, 0, 23.5, 80.2};
  ProcessView vision{"", "sarmap-vision-people", "respawning", 0, 2, 0, 0};
  state->SetProcesses("compute", {slam, vision}, common::SteadySeconds());
  MissionView mission;
  mission.state = "seeking_sound";
  mission.driven_by = "planner";
  mission.goal_kind = "sound";
  mission.has_goal = true;
  mission.goal_x_m = 2.9;
  mission.goal_y_m = 3.6;
  for (int i = 0; i <= 10; ++i) mission.path.emplace_back(4.5 - 0.16 * i, 2.0 + 0.16 * i);
  mission.frontiers = 3;
  state->SetMission(mission);
}

// Markup where the bus puts names: a keyword in PEOPLE_MAP, deputy and command names in
// PM_INFO. The page must show it as text (the headless-browser test checks that nothing runs).
inline void AddHostileStrings(ViewerState* state) {
  PersonView heard{
      7,     3.0,  3.0, ThreeSigmaEllipse(Eigen::Matrix2d::Identity() * 0.02),          0.8, false,
      false, true, 1,   "<img src=x onerror=\"document.body.dataset.pwned='keyword'\">"};
  PersonView seen{
      8,     4.0,   2.0, ThreeSigmaEllipse(Eigen::Matrix2d::Identity() * 0.01),  0.9, true,
      false, false, 1,   "<script>document.body.dataset.pwned='script'</script>"};
  state->SetPeople({heard, seen});
  ProcessView evil{
      "", "<img src=y onerror=\"document.body.dataset.pwned='command'\">", "running", 1, 0, 1, 1};
  state->SetProcesses("<img src=z onerror=\"document.body.dataset.pwned='deputy'\">", {evil},
                      common::SteadySeconds());
}

}  // namespace viewer
}  // namespace sarmap
