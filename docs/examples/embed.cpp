// embed.cpp - a generated solver in a C++ program (docs/embedding.md).
//   hbvmgen -o out models/pendulum.ham
//   cc -O2 -std=c99 -Iout -c out/pendulum.c
//   c++ -O2 -Iout embed.cpp pendulum.o -lm
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "pendulum.h"  // C linkage: the header has extern "C" guards

// The solver's state behind a small class; a failed step throws and
// leaves the state as it was.
class Pendulum {
  pendulum_state x_;

public:
  Pendulum() { pendulum_init(&x_, nullptr, nullptr); }
  double t() const { return x_.t; }
  const double *q() const { return x_.q; }
  double energy() const { return pendulum_energy(&x_, nullptr); }
  double constraint() const {
    double g[pendulum_NU];
    pendulum_constraints(&x_, nullptr, g);
    return g[0];
  }
  void step(double h) {
    int rc = pendulum_step(&x_, h, nullptr, nullptr);
    if (rc != pendulum_OK) throw std::runtime_error(pendulum_strerror(rc));
  }
};

int main() {
  Pendulum p;
  const double H0 = p.energy();
  for (int n = 0; n < 1000; n++) p.step(0.01);
  std::printf("t=%.6f x=%.9f y=%.9f dH=%.1e g=%.1e\n", p.t(), p.q()[0], p.q()[1],
              std::fabs(p.energy() - H0), std::fabs(p.constraint()));
  return 0;
}
