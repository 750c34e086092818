// What every page of ours shares: inflating the embedded plotly.js, and moving the body's
// view to a posture (the mannequin's surfaces and the traces that move with it).
"use strict";

function json(id) {
  return JSON.parse(document.getElementById(id).textContent);
}

async function loadPlotly() {
  const text = document.getElementById("plotly-gz").textContent.trim();
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  const code = await new Response(stream).text();
  const script = document.createElement("script");
  script.textContent = code;
  document.head.appendChild(script);
}

// Each mesh's vertices at moment k: world = t + R x0 for the part's frame (rows of 3 × 4).
function meshAt(mesh, placed) {
  const n = mesh.zero.length / 3;
  const x = new Array(n), y = new Array(n), z = new Array(n);
  for (const [frame, start, count] of mesh.parts) {
    const P = placed.slice(12 * frame, 12 * frame + 12);
    for (let v = start; v < start + count; v++) {
      const a = mesh.zero[3 * v], b = mesh.zero[3 * v + 1], c = mesh.zero[3 * v + 2];
      x[v] = P[0] + P[1] * a + P[2] * b + P[3] * c;
      y[v] = P[4] + P[5] * a + P[6] * b + P[7] * c;
      z[v] = P[8] + P[9] * a + P[10] * b + P[11] * c;
    }
  }
  return [x, y, z];
}

// The restyle that puts the body's view D at posture k: [update, trace indices].
function bodyAt(D, k) {
  const update = { x: [], y: [] }, traces = [];
  if (D.three) update.z = [];
  for (const mesh of D.meshes) {
    const [x, y, z] = meshAt(mesh, D.placements[k]);
    update.x.push(x); update.y.push(y); update.z.push(z);
    traces.push(mesh.trace);
  }
  for (const m of D.moving) {
    update.x.push(m.x[k]); update.y.push(m.y[k]);
    if (D.three) update.z.push(m.z[k]);
    traces.push(m.trace);
  }
  return [update, traces];
}
