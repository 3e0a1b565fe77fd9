// A mutex with priority inheritance (PTHREAD_PRIO_INHERIT), for data the SCHED_FIFO step
// thread shares with normal threads: while the step thread waits for it, the holder (the
// controller's thread issuing a command, a poll) runs at the step thread's priority, so a
// holder that the scheduler has put aside cannot hold a step back for a time slice.
#pragma once

#include <pthread.h>

namespace sweepmap {

class PriorityInheritanceMutex {
 public:
  PriorityInheritanceMutex() {
    pthread_mutexattr_t attributes;
    pthread_mutexattr_init(&attributes);
    pthread_mutexattr_setprotocol(&attributes, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&mutex_, &attributes);
    pthread_mutexattr_destroy(&attributes);
  }
  ~PriorityInheritanceMutex() { pthread_mutex_destroy(&mutex_); }
  PriorityInheritanceMutex(const PriorityInheritanceMutex&) = delete;
  PriorityInheritanceMutex& operator=(const PriorityInheritanceMutex&) = delete;
  void lock() { pthread_mutex_lock(&mutex_); }
  void unlock() { pthread_mutex_unlock(&mutex_); }

 private:
  pthread_mutex_t mutex_;
};

}  // namespace sweepmap
