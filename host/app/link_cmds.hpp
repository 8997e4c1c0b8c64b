// The link commands of the trajcore tool: `upload` (a segment stream to a
// board over a serial port, pseudo-terminal or TCP) and `board` (the loopback
// board with fault injection). Options are registered here; main.cpp runs the
// chosen one.
#pragma once
#include <CLI/CLI.hpp>

#include <limits>
#include <string>

#include "link/board.hpp"
#include "link/board_server.hpp"
#include "link/upload.hpp"
#include "stream/retick.hpp"

namespace traj::app {

struct UploadArgs {
  std::string input;                 // "-": standard input
  std::string port;
  link::UploadOptions opt;
  double max_engine_tick = stream::kMaxStepEngineTick;  // 0: the stream's own tick
  // time scaling; NaN: not given
  double feed_percent = std::numeric_limits<double>::quiet_NaN();
  double servo_period = std::numeric_limits<double>::quiet_NaN();
  bool no_auto_resume = false;
  std::string control;               // the control socket's path ("": none)
};

struct BoardArgs {
  bool loopback = false;
  int tcp_port = -1;                 // >= 0: listen on TCP (0: any free port); else a pseudo-terminal
  link::BoardOptions board;
  link::FaultOptions faults;
  std::string faults_dir = "both";
  bool once = false;                 // exit after one job's end
  std::string played;                // file: the bytes of every played record, in order
  std::string expect;                // simulated board: the stream whose prediction the pins are checked against
  // simulated board, time scaling: "AT:FOR" (s) hold pin and starved link,
  // "AT:PERCENT" FEED, in board seconds after playback starts
  std::vector<std::string> holds, starves, feeds;
};

struct LinkCommands {
  UploadArgs up;
  BoardArgs bd;
  CLI::App* upload = nullptr;
  CLI::App* board = nullptr;
};

void add_link_commands(CLI::App& app, LinkCommands& lc);
int upload_command(const UploadArgs& a);
int board_command(const BoardArgs& a);

}  // namespace traj::app
