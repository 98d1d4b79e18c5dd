#include "sigfpe_trap.h"

#include <csetjmp>
#include <csignal>
#include <mutex>

namespace squeeze::meshing::detail {
namespace {

thread_local sigjmp_buf* target = nullptr;  // where a SIGFPE on this thread returns to, if anywhere
struct sigaction previous {};                // the handler before ours, for every other SIGFPE

extern "C" void on_sigfpe(int sig, siginfo_t* info, void* context) {
  if (target) siglongjmp(*target, 1);
  // Not ours: as before (the default action ends the process; a handler of the host's runs).
  if (previous.sa_flags & SA_SIGINFO) {
    previous.sa_sigaction(sig, info, context);
    return;
  }
  if (previous.sa_handler == SIG_IGN) return;
  if (previous.sa_handler != SIG_DFL) {
    previous.sa_handler(sig);
    return;
  }
  signal(sig, SIG_DFL);
  raise(sig);
}

}  // namespace

bool run_unless_sigfpe(const std::function<void()>& f) {
  static std::once_flag installed;
  std::call_once(installed, [] {
    struct sigaction a {};
    a.sa_sigaction = on_sigfpe;
    a.sa_flags = SA_SIGINFO | SA_NODEFER;
    sigemptyset(&a.sa_mask);
    sigaction(SIGFPE, &a, &previous);
  });
  sigjmp_buf here;
  sigjmp_buf* const outer = target;
  if (sigsetjmp(here, 1) != 0) {
    target = outer;
    return false;
  }
  target = &here;
  f();
  target = outer;
  return true;
}

}  // namespace squeeze::meshing::detail
