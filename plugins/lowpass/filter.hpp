// Zero-phase low-pass filters for sampled curves (one motion channel at a time), on plain data.
// The plugin's node (lowpass_plugin.cpp) is a thin adapter over these.
//
//   std::vector<Biquad> sections = butterworth_lowpass(2, 6.0, 120.0);  // 6 Hz at 120 fps
//   FilterScratch scratch;
//   filtfilt(sections, samples, scratch);          // in place, no phase lag
//   gaussian_smooth(samples, gaussian_sigma_for_cutoff(6.0, 120.0));
//
// Both filters pass `cutoff_hz` at half amplitude (-6 dB) and leave constants exactly constant
// and straight lines straight up to the first and last sample: the signal is extended at both
// ends by odd reflection (x[-k] = 2 x[0] - x[k], as scipy.signal.filtfilt does), repeated as
// often as the padding needs, so clips shorter than the padding work too. A consequence, as in
// scipy: the first and last samples are kept as they are (the extension is point-symmetric
// about them), so noise on exactly those frames is not removed; it fades out over the filter's
// time scale towards the interior.
#pragma once

#include <span>
#include <vector>

namespace kg::lowpass {

// One second-order section, direct form II transposed, normalised so that a0 = 1:
//   y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2]
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

// Digital Butterworth low-pass of even `order` (2, 4, ...) as order/2 cascaded sections: the
// analog prototype's pole pairs mapped by the bilinear transform with the cutoff prewarped, so
// one pass is exactly -3 dB at cutoff_hz and 1 at DC. Throws std::invalid_argument unless
// order is even and positive and 0 < cutoff_hz < fps / 2 (the Nyquist frequency).
std::vector<Biquad> butterworth_lowpass(int order, double cutoff_hz, double fps);

// Reused buffers; one per thread.
struct FilterScratch {
  std::vector<double> padded;
};

// Frames of padding filtfilt puts before and after the signal: enough for the start-up transient
// of the slowest section (pole radius r) to fall below 1e-10 of its size, ln(1e-10) / ln(r), and
// at least scipy's 3 * (2 * sections + 1).
int filtfilt_padding(const std::vector<Biquad>& sections);

// Runs `sections` forward then backward over `signal` (in place), extended by `padding` frames at
// each end: zero phase, magnitude response squared (so the effective order doubles and cutoff_hz
// passes at -6 dB). Each pass starts from the sections' steady state for its first sample.
// Signals of fewer than 2 samples are left alone.
void filtfilt(const std::vector<Biquad>& sections, int padding, std::span<double> signal,
              FilterScratch& scratch);

// Standard deviation, in frames, of the Gaussian kernel whose response exp(-2 pi^2 s^2 f^2)
// (s in seconds) is 1/2 at cutoff_hz, matching a Butterworth filtfilt's -6 dB point:
// s = sqrt(ln 2 / 2) / (pi cutoff_hz). Throws std::invalid_argument unless 0 < cutoff_hz < fps / 2.
double gaussian_sigma_for_cutoff(double cutoff_hz, double fps);

// Convolves `signal` (in place) with a normalised Gaussian of `sigma_frames` (> 0), truncated
// at 4 sigma, the ends extended by odd reflection (kg::motion::gaussian_smoothed). Symmetric
// kernel: zero phase. Signals of fewer than 2 samples are left alone.
void gaussian_smooth(std::span<double> signal, double sigma_frames);

}  // namespace kg::lowpass
