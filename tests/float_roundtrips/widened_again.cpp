// A double rounded to float and widened back, in a pair that GCC vectorizes: the pattern
// scripts/find_float_roundtrips.py must find (GCC 12.2 folds it into a copy of `a`).
struct Pair {
  float x, y;
};

void widenedAgain(double* out, const double* a) {
  const Pair p{static_cast<float>(a[0]), static_cast<float>(a[1])};
  out[0] = p.x;
  out[1] = p.y;
}
