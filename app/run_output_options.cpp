#include "app/run_output_options.hpp"

#include <CLI/CLI.hpp>

namespace gapflow {

RunOutputDef RunOutputOptions::resolved() const {
  RunOutputDef d = def;
  d.view.colour_by = parse_colouring(colour);
  d.validate();
  return d;
}

void add_run_output_options(CLI::App* cmd, RunOutputOptions& o) {
  const char* group = "Seeing the run";
  cmd->add_option("--snapshot-at", o.def.snapshot_times_s,
                  "PNG top views at these times (s after release), e.g. --snapshot-at 0,5,10")
      ->delimiter(',')
      ->group(group);
  cmd->add_option("--snapshot-dir", o.def.snapshot_dir, "Folder for snapshots (created; default .)")->group(group);
  cmd->add_flag("--snapshot-on-clog", o.def.snapshot_on_clog,
                "One PNG per clog when it is detected, coloured by state: the arch the clog locator sees in red")
      ->group(group);
  cmd->add_option("--colour", o.colour, "Colour spheres by speed (with a colour bar) or state")
      ->check(CLI::IsMember({"speed", "state"}))
      ->group(group);
  cmd->add_option("--px-per-mm", o.def.view.px_per_mm, "Picture scale, px per mm of board (default 1)")->group(group);
  cmd->add_option("--speed-max", o.def.view.speed_max_m_s, "Top of the speed colour bar, m/s (default 0.5)")
      ->group(group);
  cmd->add_option("--movie", o.def.movie_path, "Encode an MP4 of the run through ffmpeg (no frames on disk)")
      ->group(group);
  cmd->add_option("--fps", o.def.movie_fps, "Movie frames per simulated second, played back in real time (default 25)")
      ->group(group);
  cmd->add_option("--vtk", o.def.vtk_dir, "Write a ParaView time series (VTK XML PolyData + run.pvd) into this folder")
      ->group(group);
  cmd->add_option("--vtk-interval", o.def.vtk_interval_s, "Simulated seconds between ParaView frames (default 0.1)")
      ->group(group);
}

}  // namespace gapflow
