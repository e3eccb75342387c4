// Times STK's Bowed waveguide for a given number of seconds at 44.1 kHz (Arco's speed peer).
// Prints the CPU seconds spent in tick() and a checksum so the loop is not optimised away.
#include <stk/Bowed.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>

int main(int argc, char **argv) {
  double seconds = argc > 1 ? std::atof(argv[1]) : 30.0;
  stk::Stk::setSampleRate(44100.0);
  stk::Bowed bowed(100.0);
  bowed.noteOn(293.66, 0.8);
  long n = static_cast<long>(seconds * 44100.0);
  double sum = 0.0;
  auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < n; ++i) sum += bowed.tick();
  auto stop = std::chrono::steady_clock::now();
  double elapsed = std::chrono::duration<double>(stop - start).count();
  std::printf("%.9f %.6e\n", elapsed, sum);
  return 0;
}
