// High-quality splatting's kernel (Botsch, Hornung, Zwicker, Kobbelt, "High-Quality Surface
// Splatting on Today's GPUs", 2005, section 3; as Potree's HQS): the weight of a splat fragment
// at squared distance r2 from the splat's centre, in radii. It falls from 1 at the centre to
// nearly 0 at the rim (1 - r^2, an Epanechnikov kernel), so neighbouring splats fade into each
// other; a floor keeps a lone splat's rim visible: the weight only has to order neighbours.
float hqsWeight(float r2) { return max(1.0 - r2, 1.0 / 64.0); }
