// The host side of the link: uploads a segment stream to a board (or the
// loopback board) over a Transport, as rtl/board/LINK.md defines: RESET,
// CONFIG, prefill, START, credits, go-back-N re-sends on NAK or timeout, END,
// then waits until the board has played the job. `--resume` continues a job
// from the board's next_seq after the tool was restarted.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "link/frame.hpp"
#include "link/record_source.hpp"
#include "link/transport.hpp"

namespace traj::link {

struct UploadOptions {
  double clock_hz = 0;             // the board's core clock, Hz; 0: as its STATUS reports (given: checked against it)
  std::vector<int> step_shift;     // per axis (one value: every axis); empty: 0
  double pulse_us = 2.0, dir_setup_us = 2.0;
  double status_period_s = 0.1;    // the board's periodic STATUS (0: on request only)
  size_t prefill = 0;              // segments stored before START (0: as many as the FIFO takes)
  bool resume = false;             // continue the board's job from its next_seq
  int timeout_ms = 100;            // answer timeout, plus the transmission time of what is in flight
  int baud = 1000000;              // for the transmission time (pseudo-terminals and TCP are faster)
  int max_retries = 20;            // re-sends of one segment, or unanswered requests, before giving up
  const std::atomic<bool>* interrupted = nullptr;  // set by SIGINT: STOP and exit
};

struct UploadProgress {
  uint64_t acked = 0;         // records the board has stored (next_seq)
  uint64_t read = 0;          // records read from the stream so far
  bool stream_done = false;   // the stream's end record was read
  uint64_t resends = 0, naks = 0, timeouts = 0;
  bool have_status = false;
  Status status;              // the latest STATUS
};

struct UploadResult {
  uint64_t records = 0, first_seq = 0;  // first_seq > 0 after --resume
  UploadProgress progress;
  double seconds = 0;
};

// Thrown with a message naming what failed; the board is left stopped or
// holding (no motion jumps).
class UploadError : public LinkError {
 public:
  using LinkError::LinkError;
};

UploadResult upload(Transport& port, RecordSource& src, const UploadOptions& o,
                    const std::function<void(const UploadProgress&)>& on_progress = {});

}  // namespace traj::link
