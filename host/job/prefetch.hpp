// SPDX-License-Identifier: Apache-2.0
// The streaming planner's curves, read and built ahead on a second thread.
//
// A streamed toolpath costs two kinds of work per curve: reading and blending
// it (the StreamSource) and building what the planner needs of it alone (the
// plan::PathCurve: arc-length table, curvature split points, cusps); then the
// windows plan, fit and compile. The first kind does not depend on the
// second, so CurvePrefetch runs it on a thread of its own, at most `capacity`
// curves ahead (memory stays bounded), while run_streaming plans. The
// PathCurve's lazily computed split points and cusps go to whichever thread
// is the faster: the reader computes them while its queue is at least half
// full, the planner otherwise. The curves,
// their order and every computed value are those of the single-threaded
// reading: only the time changes.
//
// Errors: an exception from the source or from building a curve is handed
// over in its place in the sequence and rethrown by next(), as the
// single-threaded reading would throw it there. Destroying the prefetch (also
// while an exception unwinds the planner) stops the thread and joins it.
#pragma once
#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "job/streaming.hpp"

namespace traj::job {

class CurvePrefetch {
 public:
  struct Item {
    StreamCurve curve;
    std::shared_ptr<const plan::PathCurve> built;  // with its arc-length table
  };

  // threaded false: next() reads and builds in the caller's thread.
  CurvePrefetch(StreamSource& src, size_t capacity, bool threaded);
  ~CurvePrefetch();
  CurvePrefetch(const CurvePrefetch&) = delete;
  CurvePrefetch& operator=(const CurvePrefetch&) = delete;

  // The next curve; false at the end of the path.
  bool next(Item& it);

 private:
  bool read(Item& it);  // from the source, built (the producer's step)
  bool planner_behind();  // the queue at least half full: the reader is the faster thread
  void produce();

  StreamSource& src_;
  const size_t capacity_;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  bool ended_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace traj::job
