// The plots beside the 3D view: uPlot charts of log columns against the log's time, each with a
// cursor at the time the view shows. A recorded run's columns come from csp (/api/series, decimated
// keeping each bucket's extremes); a live run's are appended frame by frame.
import uPlot from "uplot";

const colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];

export class Plot {
  // `columns`: the log's column names this plot draws; `title` with its unit.
  constructor(container, title, columns, width) {
    this.title = title;
    this.columns = columns;
    this.element = document.createElement("div");
    this.element.className = "plot";
    container.appendChild(this.element);
    this.data = [[], ...columns.map(() => [])];
    this.u = new uPlot({
      title, width, height: 160,
      // A constant column gets a range of its own (uPlot's default for one would be 0..100).
      scales: { x: { time: false }, y: { range: (u, min, max) => (min === max ? [min - 1, max + 1] : uPlot.rangeNum(min, max, 0.1, true)) } },
      legend: { live: false },
      cursor: { drag: { x: false, y: false } },
      series: [{ label: "t [s]" }, ...columns.map((name, i) => ({ label: name, stroke: colours[i % colours.length], width: 1 }))],
      axes: [{ label: "t [s]", size: 36 }, { size: 56 }],
    }, this.data, this.element);
    this.cursor = document.createElement("div");
    this.cursor.className = "cursor";
    this.u.over.appendChild(this.cursor);
  }

  // A recorded run's series: {t: [...], columns: {name: [...]}}.
  setSeries(series) {
    this.data = [series.t, ...this.columns.map((name) => series.columns[name])];
    this.u.setData(this.data);
  }

  // A live run: one sample per frame (values by column name), the last `keep` seconds shown.
  append(t, values, keep) {
    this.data[0].push(t);
    this.columns.forEach((name, i) => this.data[i + 1].push(values[name] ?? null));
    while (this.data[0].length > 2 && t - this.data[0][0] > keep) this.data.forEach((a) => a.shift());
    this.u.setData(this.data);
  }

  showTime(t) {
    const x = this.u.valToPos(t, "x");
    this.cursor.style.left = `${x}px`;
    this.cursor.style.height = `${this.u.over.clientHeight}px`;
    this.cursor.hidden = !(x >= 0 && x <= this.u.over.clientWidth);
  }
}
