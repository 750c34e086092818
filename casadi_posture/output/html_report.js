// report.html of a run: draws the body and the curves, and moves the body and the curves'
// cursor to the moment the slider picks (viewer.js before it).

function clockText(D, k) {
  const t = D.time[k];
  const when = D.unit === "min" ? `${(t / 60).toFixed(2)} min (${t} s)` : `${t} s`;
  const owner = D.owner[k] ? `, constraint on ${D.owner[k]}` : "";
  return `t = ${when}, ${D.phase[k]}${owner}`;
}

async function main() {
  await loadPlotly();
  const D = json("report-data");
  const bodyFigure = json("body-figure");
  const curvesFigure = json("curves-figure");
  const config = { responsive: true, displaylogo: false };
  const bodyDiv = document.getElementById("body");
  const curvesDiv = document.getElementById("curves");
  await Plotly.newPlot(bodyDiv, bodyFigure.data, bodyFigure.layout, config);
  const cursor = D.cursor.map((axis) => ({
    type: "line", xref: axis, yref: `y${axis.slice(1)} domain`, x0: 0, x1: 0, y0: 0, y1: 1,
    line: { color: "#333", width: 1.2 },
  }));
  const shapes = (curvesFigure.layout.shapes || []).concat(cursor);
  const first = shapes.length - cursor.length;
  curvesFigure.layout.shapes = shapes;
  await Plotly.newPlot(curvesDiv, curvesFigure.data, curvesFigure.layout, config);
  const slider = document.getElementById("slider");
  const clock = document.getElementById("clock");

  window.showFrame = function (k) {
    Plotly.restyle(bodyDiv, ...bodyAt(D, k));
    const moved = {};
    const at = D.time[k] / D.scale;
    D.cursor.forEach((_, r) => {
      moved[`shapes[${first + r}].x0`] = at;
      moved[`shapes[${first + r}].x1`] = at;
    });
    Plotly.relayout(curvesDiv, moved);
    clock.textContent = clockText(D, k);
    slider.value = k;
    window.reportFrame = k;
  };

  slider.addEventListener("input", () => window.showFrame(Number(slider.value)));
  curvesDiv.on("plotly_click", (event) => {
    const t = event.points[0].x * D.scale;
    let best = 0;
    D.time.forEach((v, k) => { if (Math.abs(v - t) < Math.abs(D.time[best] - t)) best = k; });
    window.showFrame(best);
  });
  let timer = null;
  const play = document.getElementById("play");
  play.addEventListener("click", () => {
    if (timer) { clearInterval(timer); timer = null; play.textContent = "play"; return; }
    play.textContent = "pause";
    timer = setInterval(() => {
      const k = (Number(slider.value) + 1) % D.time.length;
      window.showFrame(k);
      if (k === D.time.length - 1) { clearInterval(timer); timer = null; play.textContent = "play"; }
    }, 100);
  });
  window.showFrame(0);
  document.getElementById("loading").remove();
  window.reportReady = true;
}

main().catch((error) => {
  document.getElementById("loading").textContent = `The plots could not be drawn: ${error}`;
  console.error(error);
});
