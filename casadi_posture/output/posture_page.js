// report.html of a posture (solve, compare): draws the chosen case's body with a button per
// posture, its load chart, and shows its summary and tables; a row of the index table
// picks the case (viewer.js and sortable.js before it).

async function main() {
  await loadPlotly();
  const cases = json("cases");
  const config = { responsive: true, displaylogo: false };
  const bodyDiv = document.getElementById("body");
  const chartDiv = document.getElementById("chart");
  const buttons = document.getElementById("postures");
  let current = null;

  window.showPosture = function (k) {
    Plotly.restyle(bodyDiv, ...bodyAt(current, k));
    buttons.querySelectorAll("button").forEach((b, n) => b.classList.toggle("shown", n === k));
    window.reportPosture = k;
  };

  window.showCase = async function (c) {
    current = cases[c];
    await Plotly.react(bodyDiv, current.figure.data, current.figure.layout, config);
    if (current.chart) {
      await Plotly.react(chartDiv, current.chart.data, current.chart.layout, config);
    } else {
      Plotly.purge(chartDiv);
    }
    buttons.replaceChildren(...current.labels.map((label, k) => {
      const button = document.createElement("button");
      button.type = "button";
      button.textContent = label;
      button.addEventListener("click", () => window.showPosture(k));
      return button;
    }));
    document.querySelectorAll(".case").forEach((el) => { el.hidden = Number(el.dataset.case) !== c; });
    document.querySelectorAll("#index tbody tr").forEach((row) => {
      row.classList.toggle("chosen", Number(row.dataset.case) === c);
    });
    window.showPosture(current.labels.length - 1);
    window.reportCase = c;
  };

  document.querySelectorAll("table.sortable").forEach(sortable);
  document.querySelectorAll("#index tbody tr").forEach((row, c) => {
    row.dataset.case = c;
    row.addEventListener("click", () => window.showCase(c));
  });
  await window.showCase(0);
  document.getElementById("loading").remove();
  window.reportReady = true;
}

main().catch((error) => {
  document.getElementById("loading").textContent = `The plots could not be drawn: ${error}`;
  console.error(error);
});
