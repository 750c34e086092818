// Tables sorted by a click on a column's heading: numbers by value, then text; a second
// click reverses the order.
"use strict";

function sortable(table) {
  const heads = table.querySelectorAll("thead th");
  heads.forEach((th, column) => {
    th.addEventListener("click", () => {
      const tbody = table.tBodies[0];
      const rows = Array.from(tbody.rows);
      const up = !th.classList.contains("sorted-up");
      const key = (row) => {
        const text = row.cells[column].textContent.trim();
        const number = Number(text);
        return text !== "" && !Number.isNaN(number) ? [0, number] : [1, text];
      };
      rows.sort((a, b) => {
        const [p, q] = [key(a), key(b)];
        const order = p[0] - q[0] || (p[1] < q[1] ? -1 : p[1] > q[1] ? 1 : 0);
        return up ? order : -order;
      });
      rows.forEach((row) => tbody.appendChild(row));
      heads.forEach((h) => h.classList.remove("sorted-up", "sorted-down"));
      th.classList.add(up ? "sorted-up" : "sorted-down");
    });
  });
}
