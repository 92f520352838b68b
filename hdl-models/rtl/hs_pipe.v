// Valid/ready pipeline shell of every HDL model: DEPTH register stages of W bits behind the
// model's datapath. The pipeline stalls as a whole (no skid buffer): all stages advance
// when the last one is empty or its word is taken (en = out_ready || !out_valid), and
// in_ready = en, so a word is accepted in every cycle the source offers one and the sink
// does not hold the output back; a cycle without in_valid enters an empty stage (a
// bubble). rst empties the pipeline. Latency DEPTH clocks from acceptance to out_valid,
// one word per clock at full rate.
module hs_pipe #(
    parameter W     = 8,
    parameter DEPTH = 1
) (
    input  wire         clk,
    input  wire         rst,
    input  wire         in_valid,
    output wire         in_ready,
    input  wire [W-1:0] in_data,
    output wire         out_valid,
    input  wire         out_ready,
    output wire [W-1:0] out_data
);
    reg [W-1:0]     d [0:DEPTH-1];
    reg [DEPTH-1:0] v;
    wire en = out_ready || !v[DEPTH-1];
    assign in_ready  = en;
    assign out_valid = v[DEPTH-1];
    assign out_data  = d[DEPTH-1];
    integer s;
    always @(posedge clk) begin
        if (en) begin
            for (s = DEPTH - 1; s > 0; s = s - 1) begin
                v[s] <= v[s-1];
                d[s] <= d[s-1];
            end
            v[0] <= in_valid;
            d[0] <= in_data;
        end
        if (rst) v <= {DEPTH{1'b0}};
    end
endmodule
