// nestlight: explore and light laser scans far larger than memory.
#include "cli.h"

int main(int argc, char** argv) {
  CLI::App app{
      "nestlight: converts laser scans far larger than memory into a streamable nested octree,\n"
      "streams it into a viewer or headless renders, and lights scans and objects inserted into "
      "them\n"
      "(scene files; an Embree path-traced reference that the real-time GI methods are measured "
      "against).\n\n"
      "Typical use:\n"
      "  nestlight convert scan.las -o scan.octree     build the octree (bounded memory)\n"
      "  nestlight info scan.octree                     what was built\n"
      "  nestlight verify scan.octree                   check every byte and point\n"
      "  nestlight view scan.octree                     fly through it (window)\n"
      "  nestlight render scan.octree -o view.png       headless image (EGL, llvmpipe without a "
      "GPU)\n"
      "  nestlight demo                                 generate, convert, verify and render a "
      "scene\n"
      "  nestlight make-scene cornell -o room           a GI test scene (scan, meshes, "
      "scene.json)\n"
      "  nestlight render room/scene.json               path-traced reference of a scene, linear "
      "EXR\n"
      "  nestlight compare render.exr reference.exr     error metrics against a reference image\n"
      "  nestlight bench gi room/scene.json             speed against error of the GI methods\n"
      "  nestlight bench ibl                            IBL estimators under video light probes\n"
      "  nestlight bench diffrender dr/scene.json       differential rendering's tables (paper)\n"
      "  nestlight bench projection room/scene.json     micro-buffers against brute force (paper)\n"
      "  nestlight gl-info --programs                   the GL driver, and every shader compiled "
      "by it\n"
      "  nestlight expand-hdr scan.octree --photo p.exr HDR colour layer from one HDR photograph\n"
      "\n"
      "`nestlight <command> --help` describes a command. US spellings are read as the UK ones\n"
      "(--color, --rasterizer, --normal-neighbors, color-match).\n"
      "\n"
      "Exit codes: 0 done; 1 a user error (an unknown command or option, a bad value, an input\n"
      "file that is missing, of the wrong kind or damaged); 2 a check failed (verify, stress,\n"
      "gl-info, the demo's verify, an unusable colour-match); 3 the program or the system failed\n"
      "(out of memory, a file system error).\n",
      "nestlight"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "nestlight 0.1.0");
  int code = 0;
  nestlight::cli::addConvert(app, code);
  nestlight::cli::addInfo(app, code);
  nestlight::cli::addVerify(app, code);
  nestlight::cli::addExport(app, code);
  nestlight::cli::addProfile(app, code);
  nestlight::cli::addGenerate(app, code);
  nestlight::cli::addDemo(app, code);
  nestlight::cli::addBench(app, code);
  nestlight::cli::addStress(app, code);
  nestlight::cli::addRender(app, code);
  nestlight::cli::addView(app, code);
  nestlight::cli::addBenchRender(app, code);
  nestlight::cli::addBenchGi(app, code);
  nestlight::cli::addBenchFrame(app, code);
  nestlight::cli::addBenchProjection(app, code);
  nestlight::cli::addBenchStream(app, code);
  nestlight::cli::addMakeScene(app, code);
  nestlight::cli::addSurfels(app, code);
  nestlight::cli::addCompare(app, code);
  nestlight::cli::addExpandHdr(app, code);
  nestlight::cli::addBakeRadiance(app, code);
  nestlight::cli::addColourMatch(app, code);
  nestlight::cli::addBenchHdr(app, code);
  nestlight::cli::addBenchIbl(app, code);
  nestlight::cli::addBenchDiffrender(app, code);
  nestlight::cli::addBenchLaz(app, code);
  nestlight::cli::addBenchClip(app, code);
  nestlight::cli::addGlInfo(app, code);
  // Parse errors and user errors exit 1, failed checks 2, failures of the program or the
  // system 3 (cli.h: ExitCode); --help and --version 0.
  return nestlight::cli::runCommandLine(app, argc, argv, code);
}
